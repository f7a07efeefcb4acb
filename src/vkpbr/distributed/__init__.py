"""Render many views across GPUs and machines on Ray: resumable and exactly once.

    import vkpbr.distributed
    result = vkpbr.distributed.render("job.json")          # a local Ray instance
    result = vkpbr.distributed.render(job, address="head:6379")
    print("\\n".join(result.summary()))

A job (vkpbr.distributed.job) is a list of scene entries (scene, poses, outputs, size, out),
cut into work items of a few views; one renderer actor per GPU (or per CPU worker on
lavapipe) renders them and writes the files; the driver records each finished or failed item
in a manifest in the entry's out folder, so a re-run renders only what is missing. See
docs/distributed.md. Needs the `ray` extra (`pip install 'vkpbr[ray]'`); this package imports
without it, and says so in one line when a job starts.
"""

from __future__ import annotations

from vkpbr.distributed.driver import ClusterError, Failure, JobResult, check_job, render
from vkpbr.distributed.job import Job, RenderSettings, SceneJob, WorkItem, job_from_doc, load_job
from vkpbr.distributed.manifest import MANIFEST_NAME, Manifest

__all__ = ["render", "JobResult", "Failure", "ClusterError", "check_job", "Job", "SceneJob",
           "RenderSettings", "WorkItem", "load_job", "job_from_doc", "Manifest", "MANIFEST_NAME"]
