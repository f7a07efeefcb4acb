"""A renderer process's main (`vkpbr batch --processes`): the worker that
vkpbr.distributed.processes.ProcessActor starts as `python -c WORKER ENCODERS LOG_LEVEL DEVICE` (DEVICE "": the default).

It renders the work items it is sent with one RendererActor and answers each with the
actor's result dict; its diagnostics are the CLI's one-line records on stderr (app/log.py) at
the driver's level. The protocol: pickled (item, ahead) requests on stdin, pickled results
in the same order on the stdout it was started with, which it keeps for its answers alone
(its own stdout then points at stderr, so nothing printed by Python or a Vulkan layer can
corrupt them); end of input ends it.
"""

from __future__ import annotations

import functools
import logging
import os
import pickle
import queue
import signal
import sys
import threading
from typing import IO

from vkpbr.app.log import cli_logging
from vkpbr.distributed.actor import RendererActor
from vkpbr.distributed.job import RenderSettings

__all__ = ["serve"]


def serve() -> None:
    """The worker's loop: a request at a time, its result back, in order; argv: encoders,
    log level, device (an index or a name part; empty: the default).

    The driver keeps processes.DEPTH requests in flight, so the next item is often here
    before this one's views are rendered: when it is of another scene, the renderer changes
    to it while this item's files encode (RendererActor.render's `upcoming`; the in-process
    driver's `switch`), and the scene after it starts loading then."""
    # Ctrl-C reaches a terminal's whole process group: the driver handles it (ending its
    # workers at once, their files atomic), so a worker neither stops on it nor prints a
    # traceback of its own.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    answers = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # prints (and layers') to stderr
    encoders, level, device = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    verbosity = {logging.ERROR: -1, logging.WARNING: 0, logging.INFO: 1}.get(level, 2)
    requests: queue.Queue = queue.Queue()
    threading.Thread(target=_read_requests, args=(sys.stdin.buffer, requests),
                     name="vkpbr-requests", daemon=True).start()
    with cli_logging(verbosity):  # (each item runs under actor.quick_switches)
        actor = RendererActor(int(device) if device.isdigit() else device or None,
                              encoders=encoders)
        try:
            while (request := requests.get()) is not None:
                item, ahead = request
                res = actor.render(item, ahead, upcoming=functools.partial(
                    _upcoming, requests, item.settings.scene_key()))
                try:
                    pickle.dump(res, answers, pickle.HIGHEST_PROTOCOL)
                    answers.flush()
                except OSError:  # the driver is gone (killed): nobody to answer, end quietly
                    return
        finally:
            actor.close()


def _read_requests(stream: IO[bytes], requests: queue.Queue) -> None:
    """Requests from `stream` into `requests`, then None (end of input, or a torn one)."""
    try:
        while True:
            requests.put(pickle.load(stream))
    except Exception:  # noqa: BLE001 - EOFError: the driver closed it (or ended)
        requests.put(None)


def _upcoming(requests: queue.Queue, key: tuple
              ) -> tuple[RenderSettings, RenderSettings | None] | None:
    """(the next request's settings, its scene to load ahead) when that request is here
    already (left in the queue) and of another scene than `key`, else None."""
    with requests.mutex:
        following = requests.queue[0] if requests.queue else None
    if following is None or following[0].settings.scene_key() == key:
        return None
    return following[0].settings, following[1]
