"""Issue 11, class 3, as a fuzz format: every (target, trick) of tests/fuzzing.py's path
tricks, with and without --allow-outside-paths, loaded (and its textures decoded) under the
PathGuard audit hook: a clean one-line error naming the scene file, or the missing-texture
fallback, never an open of a file outside the scene's folder or of a non-regular file."""

from __future__ import annotations

import collections
import logging

import pytest
from fuzzing import (
    PATH_TARGETS,
    PATH_TRICKS,
    Corpus,
    Forbidden,
    PathGuard,
    PathTrickCorpus,
    run_path_trick,
)

from vkpbr.errors import SceneError
from vkpbr.scene.loader import load_scene


@pytest.fixture(scope="module")
def tricks(tmp_path_factory: pytest.TempPathFactory) -> PathTrickCorpus:
    folder = tmp_path_factory.mktemp("tricks")
    return PathTrickCorpus(folder / "pt", Corpus(folder))


@pytest.fixture(autouse=True)
def _quiet() -> None:
    logger = logging.getLogger("vkpbr")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    yield
    logger.setLevel(level)


@pytest.mark.timeout(120)  # a FIFO opened blocking would hang here
@pytest.mark.parametrize("allow", [False, True], ids=["default", "allow-outside-paths"])
def test_no_path_trick_reads_outside_or_a_special_file(tricks: PathTrickCorpus, allow: bool) -> None:
    cases = tricks.cases()
    assert len(cases) == len(PATH_TARGETS) * len(PATH_TRICKS) == 150
    outcomes: dict[tuple[str, str], str] = {}
    unclean = []
    for target, name, ref in cases:
        outcome, detail = run_path_trick(tricks, target, ref, allow_outside=allow)
        outcomes[target, name] = outcome
        if outcome == "unclean":
            unclean.append(detail)
    assert not unclean, "\n".join(unclean)
    # The control stays inside and loads; a buffer or material library the policy refuses is
    # an error (the geometry cannot be had without it); images fall back and load.
    assert all(outcomes[t, "inside (control: loads)"] == "loaded" for t, _ in PATH_TARGETS)
    refused = ["dotdot", "absolute", "percent-encoded dotdot", "symlink to a file outside",
               "FIFO", "/dev/zero", "folder", "path of 5,000 characters"]
    if not allow:
        assert [outcomes["glTF buffer", n] for n in refused] == ["clean"] * len(refused)
    for name in ("FIFO", "/dev/zero", "symlink to /dev/zero", "folder"):  # never opened
        assert outcomes["glTF buffer", name] == "clean"
        assert outcomes["OBJ mtllib", name] == "clean"
        for image_target in ("glTF image", "MTL map", ".comp5822mesh texture", ".vkpbr image"):
            assert outcomes[image_target, name] == "loaded"  # the missing-texture fallback


@pytest.mark.parametrize("target", [t for t, _ in PATH_TARGETS])
def test_the_messages_name_the_scene_and_the_option(tricks: PathTrickCorpus, target: str) -> None:
    """Refused geometry files name the scene file, the reference and --allow-outside-paths;
    refused textures are counted in the scene's one warning line, naming the same."""
    path = tricks.write(target, tricks.reference("../outside/secret.{e}", dict(PATH_TARGETS)[target]))
    if target in ("glTF buffer", "OBJ mtllib"):
        what = "buffer 0" if target == "glTF buffer" else "material library"
        with pytest.raises(SceneError) as info:
            load_scene(path)
        assert str(info.value) == (
            f"{path}: {what} refers to ../outside/secret.{dict(PATH_TARGETS)[target]} outside "
            "the scene's folder; pass --allow-outside-paths (allow_outside_paths=True) to read it")
    else:
        with pytest.raises(SceneError, match=r"pt\.\w+: 1 of 1 textures outside the scene's "
                                             r"folder \(first: \.\./outside/secret\.png; pass "
                                             r"--allow-outside-paths"):
            load_scene(path, strict=True)


def test_the_guard_catches_a_loader_that_reads_outside(tricks: PathTrickCorpus,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """The suite can fail: with the folder rule switched off inside the loader (but not in the
    guard), the outside buffer is opened, the guard stops the open and the input is unclean."""
    import dataclasses

    from vkpbr.scene.resources import ResourcePolicy

    real = ResourcePolicy.resolve
    monkeypatch.setattr(ResourcePolicy, "resolve", lambda self, *a, **k: real(
        dataclasses.replace(self, allow_outside=True), *a, **k))
    outcome, detail = run_path_trick(tricks, "glTF buffer", "../outside/secret.bin")
    assert outcome == "unclean"
    assert detail.endswith(f"opened a file outside the scene's folder: "
                           f"{tricks.outside.resolve() / 'secret.bin'}"), detail
    guard = PathGuard.get()
    guard.arm(tricks.root, tricks.scene_dir, allow_outside=True)
    try:  # a FIFO is forbidden even with the flag, before open() could block
        with pytest.raises(Forbidden):
            open(tricks.scene_dir / "fifo.bin", "rb")  # noqa: SIM115
    finally:
        assert guard.disarm() == [f"opened a file that is not regular: "
                                  f"{(tricks.scene_dir / 'fifo.bin').resolve()}"]
    counts = collections.Counter(run_path_trick(tricks, "glTF buffer", "ok.bin")[0] for _ in "ab")
    assert counts == {"loaded": 2}  # disarmed between runs, re-armed by each
