"""The viewer's animation playback: which of the scene's glTF animations plays, how fast, and
the time it has reached (app/viewer.py asks `advance` each frame and poses the scene with
Renderer.set_time). No window code here: the keys (app/keys.py) call its methods.

It starts playing every animation at once (as the Khronos Sample Viewer plays a file's first
animation; "all" also plays files whose parts are split over several), looping over the
longest's duration. Y steps through "all" and each animation by name.
"""

from __future__ import annotations

from typing import Any

__all__ = ["Playback", "SPEEDS"]

SPEEDS = (0.125, 0.25, 0.5, 1.0, 2.0, 4.0)


class Playback:
    """Animation playback of `scene` (a Scene with `animations`)."""

    def __init__(self, scene: Any) -> None:
        self.names = [a.name for a in getattr(scene, "animations", [])]
        self.durations = [float(a.duration) for a in getattr(scene, "animations", [])]
        self.index: int | None = None  # None: every animation
        self.playing = bool(self.names)
        self.speed_step = SPEEDS.index(1.0)
        self.time = 0.0
        self._posed: tuple[float, int | None] | None = None

    @property
    def animation(self) -> int | None:
        return self.index

    @property
    def speed(self) -> float:
        return SPEEDS[self.speed_step]

    @property
    def duration(self) -> float:
        if not self.durations:
            return 0.0
        return self.durations[self.index] if self.index is not None else max(self.durations)

    def toggle(self) -> None:
        self.playing = bool(self.names) and not self.playing

    def next(self, step: int = 1) -> None:
        """The next (step 1) or previous (-1) choice among "all" and each animation."""
        if self.names:
            choices = [None, *range(len(self.names))]
            self.index = choices[(choices.index(self.index) + step) % len(choices)]
            self.time = 0.0

    def faster(self, step: int = 1) -> None:
        self.speed_step = max(0, min(len(SPEEDS) - 1, self.speed_step + step))

    def seek(self, seconds: float) -> None:
        self.time = max(0.0, float(seconds))

    def advance(self, dt: float) -> float | None:
        """Move on by `dt` seconds of wall time when playing (looping over the duration);
        the time to pose the scene at, or None when the pose already shown is current."""
        if not self.names:
            return None
        if self.playing:
            d = self.duration
            self.time = (self.time + dt * self.speed) % d if d > 0 else 0.0
        key = (self.time, self.index)
        if key == self._posed:
            return None
        self._posed = key
        return self.time

    def label(self) -> str:
        """The HUD's line."""
        if not self.names:
            return "no animation"
        name = "all" if self.index is None else (self.names[self.index] or f"#{self.index}")
        state = "playing" if self.playing else "paused"
        return (f"animation {name} ({len(self.names)})  {self.time:.2f} / {self.duration:.2f} s  "
                f"x{self.speed:g} {state}")
