"""Frames declared as steps: barriers, layout transitions and renderings derived, not written.

A `Step` names the images and buffers it touches and how (a `USES` entry: "sampled",
"storage", "color_attachment", "transfer_src", ...), says whether it draws inside a dynamic
rendering (`Rendering`: which images are its colour and depth attachments, cleared or loaded)
and carries a function that records its commands. `record_steps` walks a list of steps in
order and, before each, emits the one vkCmdPipelineBarrier2 that its declared uses need
after what earlier steps did (write after read or write, read after write, a new layout),
begins and ends renderings (consecutive steps of one `Rendering` share one), and writes a
timestamp after each timed step. A step may name the pipelines its commands bind
(`kernels`: calls that make them); `record_steps` makes every step's at once on threads
before recording, so that a first recording waits for the driver's slowest compile rather
than for the sum of them. This is Filament's FrameGraph and Vulkan-Samples'
RenderPipeline in small: the order is the list's, resources are the caller's.

A recorded frame is replayed after whatever frame came before it, so the first use of a
resource in a frame waits for every earlier command that can have touched it (every write
made available) and discards its contents (UNDEFINED). Every earlier command but copies:
a frame's readback copy (0.16 ms at 1080p on the H200) then runs beside the next frame's
first steps instead of before them. A resource that a copy can touch last in a recording (a
readback's images and buffers) says so (`copied`), and its first use waits for every
earlier command; where one that does not say so ends a recording copied, `record_steps`
closes the recording with a barrier after that copy (correct, only slower: `TAIL_WAITS`
counts them). For the same reason a frame's early clears are kernels, not vkCmdFillBuffer:
a fill is a "transfer_dst" use (COPY | CLEAR: validation layers before 1.3.275 count it a
copy), so what follows one waits for every earlier copy. Submissions made outside the graph
(uploads) end with their own barriers for any later command. What keeps contents between
frames (the shadow maps' layers that are not redrawn, a mip chain's levels) is transitioned
by the step that owns it, and told to the graph by the step's `leaves`.

This module knows Vulkan and nothing of the renderer: resource and step names are the
caller's.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from vkpbr.gpu.commands import Commands
from vkpbr.gpu.compute import make_at_once
from vkpbr.gpu.rendering import (
    Attachments,
    barriers,
    begin_rendering,
    buffer_barrier,
    end_rendering,
    image_barrier,
)

__all__ = ["Use", "USES", "ImageResource", "BufferResource", "Rendering", "Step",
           "record_steps", "build_kernels", "Tracker"]


@dataclass(frozen=True)
class Use:
    """One way a step touches a resource, in Vulkan's terms (names of VK_* constants)."""

    stages: tuple[str, ...]
    accesses: tuple[str, ...]
    layout: str | None  # images only: the layout the use needs
    writes: bool


_DEPTH_TESTS = ("EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS")
_SHADERS = ("FRAGMENT_SHADER", "COMPUTE_SHADER")
USES: dict[str, Use] = {
    "color_attachment": Use(("COLOR_ATTACHMENT_OUTPUT",),
                            ("COLOR_ATTACHMENT_WRITE", "COLOR_ATTACHMENT_READ"),
                            "COLOR_ATTACHMENT_OPTIMAL", True),
    "depth_attachment": Use(_DEPTH_TESTS,
                            ("DEPTH_STENCIL_ATTACHMENT_WRITE", "DEPTH_STENCIL_ATTACHMENT_READ"),
                            "DEPTH_ATTACHMENT_OPTIMAL", True),
    "sampled": Use(_SHADERS, ("SHADER_SAMPLED_READ",), "SHADER_READ_ONLY_OPTIMAL", False),
    "storage_read": Use(("COMPUTE_SHADER",), ("SHADER_STORAGE_READ",), "GENERAL", False),
    "fragment_storage_read": Use(("FRAGMENT_SHADER",), ("SHADER_STORAGE_READ",), "GENERAL", False),
    "storage": Use(("COMPUTE_SHADER",), ("SHADER_STORAGE_READ", "SHADER_STORAGE_WRITE"),
                   "GENERAL", True),
    # Storage buffers read by vertex shaders (a batch's lists of visible views).
    "vertex_read": Use(("VERTEX_SHADER",), ("SHADER_STORAGE_READ",), None, False),
    "indirect": Use(("DRAW_INDIRECT",), ("INDIRECT_COMMAND_READ",), None, False),
    "transfer_src": Use(("COPY",), ("TRANSFER_READ",), "TRANSFER_SRC_OPTIMAL", False),
    "transfer_dst": Use(("COPY", "CLEAR"), ("TRANSFER_WRITE",), "TRANSFER_DST_OPTIMAL", True),
    # vkCmdClearColorImage on an image then written as storage: GENERAL serves both.
    "clear": Use(("CLEAR",), ("TRANSFER_WRITE",), "GENERAL", True),
    "host_read": Use(("HOST",), ("HOST_READ",), None, False),
    "present": Use((), (), "PRESENT_SRC_KHR", False),
}
_ATTACHMENT_USES = ("color_attachment", "depth_attachment")
# What a first use of a resource that is not `copied` waits for: every stage but copies
# (and the host's, which fences order).
_BEFORE = ("ALL_GRAPHICS", "COMPUTE_SHADER", "CLEAR", "BLIT", "RESOLVE")
TAIL_WAITS: dict[str, int] = {}  # resource name -> recordings closed after its copy (see above)


def _flags(vk: Any, kind: str, names: tuple[str, ...]) -> int:
    out = 0
    for name in names:
        out |= getattr(vk, f"VK_{kind}_2_{name}_BIT")
    return out


@dataclass(frozen=True)
class _Mask:
    """A use (or a "|"-joined union of uses) as Vulkan flags."""

    stages: int
    accesses: int
    layout: int | None
    writes: bool


def _mask(vk: Any, use: str, cache: dict[str, _Mask]) -> _Mask:
    if use not in cache:
        stages = accesses = 0
        layout, writes = None, False
        for name in use.split("|"):
            u = USES[name]
            stages |= _flags(vk, "PIPELINE_STAGE", u.stages)
            accesses |= _flags(vk, "ACCESS", u.accesses)
            if u.layout is not None:
                value = getattr(vk, f"VK_IMAGE_LAYOUT_{u.layout}")
                # Two layouts: a buffer's use only (an image's is refused in Tracker.use).
                layout = value if layout in (None, value) else -1
            writes |= u.writes
        cache[use] = _Mask(stages or vk.VK_PIPELINE_STAGE_2_NONE, accesses, layout, writes)
    return cache[use]


@dataclass(eq=False)
class ImageResource:
    """An image a graph tracks: `handle` (VkImage), whether it is a depth image, how many
    layers and mip levels its barriers cover; `view` is what a rendering attaches; `msaa` the
    multisampled image drawn into and resolved into this one; `extent` its size where it is
    not the frame's (a rendering into it covers that). Its contents are discarded at each
    frame's first use. `copied`: a copy can be its last use in a recording (a readback)."""

    handle: Any
    depth: bool = False
    layers: int = 1
    levels: int = 1
    view: Any = None
    msaa: ImageResource | None = None
    extent: tuple[int, int] | None = None  # where it differs from the frame's (a rendering's area)
    copied: bool = False


@dataclass(eq=False)
class BufferResource:
    """A buffer a graph tracks (a gpu.buffer.Buffer: `handle`, `size`); `copied`: a copy can
    be its last use in a recording (a readback buffer)."""

    buffer: Any
    copied: bool = False


@dataclass(frozen=True, eq=False)
class Rendering:
    """A dynamic rendering over named attachments (resource names), cleared where a clear
    value is given and loaded otherwise. Consecutive steps with the same Rendering object
    draw inside one rendering."""

    color: str | None
    depth: str | None
    clear_color: tuple[float, ...] | None = None
    clear_depth: float | None = None
    layers: int = 1
    store_depth: bool = True


@dataclass(frozen=True, eq=False)
class Step:
    """One step of a frame: `uses` ((resource name, use), ...; a use may join several with
    "|"), drawn inside `rendering` where given (its attachments are used implicitly),
    `record(cmd)` its commands; `timed`: a timestamp follows it (FrameStats.pass_ms[name]);
    `leaves`: (resource, use) the step's own commands leave a resource in (a mip chain
    blitted and left sampled), so no barrier is derived for that change. `kernels`: calls
    that make (or return, once made) the pipelines `record` binds, made ahead of recording
    (`build_kernels`)."""

    name: str
    record: Callable[[Commands], None] = lambda cmd: None
    uses: tuple[tuple[str, str], ...] = ()
    rendering: Rendering | None = None
    timed: bool = True
    leaves: tuple[tuple[str, str], ...] = ()
    kernels: tuple[Callable[[], Any], ...] = ()

    def all_uses(self) -> tuple[tuple[str, str], ...]:
        """The declared uses and the rendering's attachments."""
        r = self.rendering
        if r is None:
            return self.uses
        implied = tuple((n, u) for n, u in ((r.color, "color_attachment"),
                                            (r.depth, "depth_attachment")) if n is not None)
        return implied + self.uses


@dataclass
class _State:
    layout: int
    write: tuple[int, int] | None = None  # (stages, accesses) of the last write
    read_stages: int = 0  # stages that read since the last write
    visible: tuple[int, int] = (0, 0)  # (stages, accesses) the last write is visible to
    use: str = ""  # the last use's name
    scope: int = -1  # the rendering it was last attached in


@dataclass
class Tracker:
    """What each resource's last use in this recording was, and the barriers that follow."""

    vk: Any
    resources: Mapping[str, ImageResource | BufferResource]
    states: dict[int, _State] = field(default_factory=dict)
    masks: dict[str, _Mask] = field(default_factory=dict)
    images: list[Any] = field(default_factory=list)
    buffers: list[Any] = field(default_factory=list)
    seen: dict[int, tuple[str, ImageResource | BufferResource]] = field(default_factory=dict)
    before: int = field(init=False, default=0)  # _BEFORE's stages (a first use's wait)

    def __post_init__(self) -> None:
        self.before = _flags(self.vk, "PIPELINE_STAGE", _BEFORE)

    def use(self, name: str, use: str, scope: int = -1) -> None:
        """Queue the barrier `use` of resource `name` needs (none when nothing came before
        it that it must wait for); `scope`: the rendering it is attached in."""
        res = self.resources[name]
        self.seen.setdefault(id(res), (name, res))
        self._use(res, use, scope)
        if isinstance(res, ImageResource) and res.msaa is not None and use in _ATTACHMENT_USES:
            self._use(res.msaa, use, scope)  # drawn into, resolved into `res`

    def _use(self, res: ImageResource | BufferResource, use: str, scope: int) -> None:
        vk, m = self.vk, _mask(self.vk, use, self.masks)
        key = id(res)
        state = self.states.get(key)
        image = isinstance(res, ImageResource)
        layout = m.layout if image else None
        if layout == -1:
            raise ValueError(f"use {use!r} asks two layouts of one image")
        if state is None:  # the frame's first use: after every earlier command (but copies)
            before = vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT if res.copied else self.before
            self._barrier(res, (before, vk.VK_ACCESS_2_MEMORY_WRITE_BIT), m,
                          vk.VK_IMAGE_LAYOUT_UNDEFINED)
            self.states[key] = self._after(m, use, scope, layout)
            return
        attached_again = (use == state.use and use in _ATTACHMENT_USES and scope == state.scope
                          and scope >= 0)
        if attached_again:
            return  # one rendering: attachment accesses are in rasterisation order
        new_layout = image and layout is not None and layout != state.layout
        waits: tuple[int, int] | None = None
        if m.writes or new_layout:
            stages = state.read_stages | (state.write[0] if state.write else 0)
            if stages or new_layout:
                waits = (stages or vk.VK_PIPELINE_STAGE_2_NONE,
                         state.write[1] if state.write else 0)
        elif state.write is not None:
            seen_stages, seen_access = state.visible
            if m.stages & ~seen_stages or m.accesses & ~seen_access:
                waits = state.write
        if waits is not None:
            self._barrier(res, waits, m, state.layout if image else None)
        if m.writes:
            self.states[key] = self._after(m, use, scope, layout if image else state.layout)
            return
        state.read_stages |= m.stages
        if waits is not None:
            state.visible = (state.visible[0] | m.stages, state.visible[1] | m.accesses)
        if image and layout is not None:
            state.layout = layout
        state.use, state.scope = use, scope

    def _after(self, m: _Mask, use: str, scope: int, layout: int | None) -> _State:
        write = (m.stages, m.accesses) if m.writes else None
        return _State(layout=layout if layout is not None else 0, write=write,
                      read_stages=0 if m.writes else m.stages,
                      visible=(m.stages, m.accesses) if not m.writes else (0, 0),
                      use=use, scope=scope)

    def leave(self, name: str, use: str) -> None:
        """Resource `name` is now as `use` left it (the step's own barriers did that)."""
        res = self.resources[name]
        self.seen.setdefault(id(res), (name, res))
        m = _mask(self.vk, use, self.masks)
        self.states[id(res)] = _State(layout=m.layout or 0, write=None, read_stages=m.stages,
                                      visible=(m.stages, m.accesses), use=use)

    def _barrier(self, res: ImageResource | BufferResource, src: tuple[int, int], m: _Mask,
                 old: int | None) -> None:
        vk = self.vk
        dst = (m.stages, m.accesses)
        if isinstance(res, BufferResource):
            self.buffers.append(buffer_barrier(vk, res.buffer, src, dst))
            return
        new = m.layout if m.layout is not None else old
        self.images.append(image_barrier(vk, res.handle, res.depth, old, new, src, dst,
                                         layers=res.layers, levels=res.levels))

    def close(self, cmd: Commands) -> None:
        """After the last step: a barrier from the copies that touched a resource last that
        is not `copied`, to every later command, since the next recording's first use of it
        will not wait for copies."""
        vk = self.vk
        outside = vk.VK_PIPELINE_STAGE_2_COPY_BIT | vk.VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT
        later = (vk.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                 vk.VK_ACCESS_2_MEMORY_READ_BIT | vk.VK_ACCESS_2_MEMORY_WRITE_BIT)
        for key, (name, res) in self.seen.items():
            state = self.states[key]
            stages = state.read_stages | (state.write[0] if state.write else 0)
            if res.copied or not stages & outside:
                continue
            src = (stages & ~vk.VK_PIPELINE_STAGE_2_HOST_BIT,
                   state.write[1] if state.write else vk.VK_ACCESS_2_NONE)
            image = isinstance(res, ImageResource)
            self._barrier(res, src, _Mask(*later, state.layout if image else None, False),
                          state.layout if image else None)
            TAIL_WAITS[name] = TAIL_WAITS.get(name, 0) + 1
        self.flush(cmd)

    @property
    def pending(self) -> bool:
        return bool(self.images or self.buffers)

    def flush(self, cmd: Commands) -> None:
        """Record the queued barriers as one vkCmdPipelineBarrier2."""
        if self.pending:
            barriers(cmd, self.images, self.buffers)
            self.images, self.buffers = [], []


def _attachments(r: Rendering, resources: Mapping[str, Any], extent: tuple[int, int]
                 ) -> Attachments:
    color = resources[r.color] if r.color is not None else None
    depth = resources[r.depth] if r.depth is not None else None
    own = (color or depth).extent  # type: ignore[union-attr]
    att = Attachments(color.view if color else None, depth.view if depth else None,
                      own or extent)
    if color is not None and color.msaa is not None:
        att.msaa_color = color.msaa.view
    if depth is not None and depth.msaa is not None:
        att.msaa_depth = depth.msaa.view
    return att


def build_kernels(steps: Sequence[Step]) -> None:
    """Make every step's `kernels` now, at once (gpu/compute.py's `make_at_once`): the
    driver's compiles (0.01-0.48 s each for the compute path's on the H200, 2.7 s in a row
    for Sponza's first frame) overlap. The pipelines' makers share their kept handles
    (gpu/kept.py: a second maker of one definition waits for the first)."""
    make_at_once([make for step in steps for make in step.kernels])


def record_steps(cmd: Commands, steps: Sequence[Step],
                 resources: Mapping[str, ImageResource | BufferResource],
                 extent: tuple[int, int], stamp: Callable[[str], None] = lambda name: None,
                 build: bool = True) -> Tracker:
    """Record `steps` in order into `cmd` with the barriers their uses need, their renderings
    begun and ended, and `stamp(name)` after each timed step. Returns the tracker (tests read
    what it derived). Every step's `kernels` are made first (`build_kernels`) unless `build`
    is False (the caller knows them made: a recording of steps recorded before, whose
    threads would cost more than the look-ups)."""
    if build:
        build_kernels(steps)
    tracker = Tracker(cmd.vk, resources)
    open_scope: Rendering | None = None
    scopes = 0
    for step in steps:
        same_scope = step.rendering is not None and step.rendering is open_scope
        scope = scopes - 1 if same_scope else scopes
        for name, use in step.all_uses():
            tracker.use(name, use, scope)
        if open_scope is not None and (not same_scope or tracker.pending):
            end_rendering(cmd)
            open_scope = None
            if same_scope:  # a barrier inside a rendering is not allowed: begin it again
                raise ValueError(f"step {step.name!r} needs a barrier inside its rendering")
        tracker.flush(cmd)
        if step.rendering is not None and open_scope is None:
            r = step.rendering
            begin_rendering(cmd, _attachments(r, resources, extent), r.clear_color,
                            r.clear_depth, r.store_depth, r.layers)
            open_scope = r
            scopes += 1
        step.record(cmd)
        for name, use in step.leaves:
            tracker.leave(name, use)
        if step.timed:
            stamp(step.name)
    if open_scope is not None:
        end_rendering(cmd)
    tracker.flush(cmd)
    tracker.close(cmd)
    return tracker
