"""Running a reconstruction (``tagsplat.start_train``) as a modal operator: the job trains on
its own thread while a window-manager timer polls it, shows its progress in the status bar and
the progress cursor, and Esc cancels it (the engine stops at its next iteration and keeps the
finished frames, so running again resumes). When it is done, OUT/sequence.pc2 is imported onto
an object.

The steps are module functions of the operator (``begin``, ``step``, ``end``) so that the same
code runs modal (``invoke``), blocking (``execute``, for scripts and ``blender -b``), and under
a test that delivers the events itself.
"""

import os
import time

import bpy

from . import engine, sequence_import

# How often the timer polls the job, seconds: often enough for a live status bar, rare enough
# that Blender's UI does not notice.
POLL_SECONDS = 0.25

# The exports' up axis asked of the engine: Blender's own, so the result needs no turning.
EXPORT_UP = "z"


def _frames(op):
    """The operator's frame range as ``start_train`` takes it: (first, end) or None for all."""
    return (op.frame_first, op.frame_end) if op.use_frames else None


def begin(op, context):
    """Starts the job of ``op``'s settings and the progress display; ``op._run`` holds the job.
    Raises what ``start_train`` raises (a missing dataset, an OUT another run is writing)."""
    for name, value in (("dataset", op.data), ("output", op.out)):
        if not value:
            raise engine.UserError(f"no {name} folder chosen: set its path")
    ts = engine.module(context)
    data, out = (os.path.normpath(bpy.path.abspath(p)) for p in (op.data, op.out))
    config = bpy.path.abspath(op.config) if op.config else None
    job = ts.start_train(
        engine.gpu_context(context), data, out, config=config, frames=_frames(op), up=EXPORT_UP
    )
    op._run = {"job": job, "out": out, "cancelling": False, "latest": None}
    context.window_manager.progress_begin(0.0, 1.0)


def describe(progress, cancelling):
    """The status bar's line for ``progress`` (None before the job's first report)."""
    if cancelling:
        return "tagsplat: cancelling at the next iteration..."
    if progress is None:
        return "tagsplat: starting... (Esc cancels)"
    loss = "" if progress.loss is None else f", loss {progress.loss:.4g}"
    return (
        f"tagsplat: {progress.stage}, frame {progress.frame} (of {progress.frames_end}), iteration "
        f"{progress.iteration}/{progress.iterations}{loss}, {progress.elapsed_s:.0f} s (Esc cancels)"
    )


def fraction(progress, first):
    """How far the job is, in [0, 1]: finished frames since ``first`` plus the current
    frame's share of iterations, over the frames asked for."""
    frames = max(progress.frames_end - first, 1)
    within = progress.iteration / progress.iterations if progress.iterations else 0.0
    return min(max((progress.frame - first + within) / frames, 0.0), 1.0)


def show(op, context):
    """Puts the latest progress in the status bar and the progress cursor."""
    run = op._run
    if run["latest"] is not None:
        first = op.frame_first if op.use_frames else 0
        context.window_manager.progress_update(fraction(run["latest"], first))
    if context.workspace is not None:
        context.workspace.status_text_set(describe(run["latest"], run["cancelling"]))


def step(op, context):
    """Polls the job once; None while it runs, else the operator's result (``end``'s)."""
    run = op._run
    progress = run["job"].poll()
    if progress is not None:
        run["latest"] = progress
    show(op, context)
    return end(op, context) if run["job"].done else None


def end(op, context):
    """Takes the finished job's result: imports OUT/sequence.pc2 when asked, reports a
    cancellation as a warning and any failure as an error; clears the progress display."""
    run = op._run
    context.window_manager.progress_end()
    if context.workspace is not None:
        context.workspace.status_text_set(None)
    try:
        run["job"].wait()
    except engine.module(context).CancelledError:
        op.report({"WARNING"}, f"cancelled; {run['out']} keeps its finished frames, run again to resume")
        return {"CANCELLED"}
    if op.import_result:
        path = os.path.join(run["out"], "sequence.pc2")
        obj = sequence_import.import_sequence(context, path, EXPORT_UP.upper(), frame_start=op.scene_frame)
        op.report({"INFO"}, f"reconstructed {run['out']}; imported onto {obj.name}")
    else:
        op.report({"INFO"}, f"reconstructed {run['out']}")
    return {"FINISHED"}


def run_to_end(op, context):
    """Polls the started job as the timer would until it ends; ``end``'s result."""
    while (result := step(op, context)) is None:
        time.sleep(POLL_SECONDS)
    return result


def cancel(op, context):
    """Asks the job to stop; ``step`` then sees it finish and ``end`` reports it."""
    op._run["cancelling"] = True
    op._run["job"].cancel()
    show(op, context)


class TAGSPLAT_OT_train(bpy.types.Operator):
    """Reconstruct a mesh sequence from a multi-view dataset with tagsplat (Esc cancels)"""

    bl_idname = "tagsplat.train"
    bl_label = "Reconstruct"
    bl_options = {"REGISTER"}

    data: bpy.props.StringProperty(name="Dataset", description="The dataset folder", subtype="DIR_PATH")
    out: bpy.props.StringProperty(
        name="Output", description="The output folder (a run into a finished one resumes)", subtype="DIR_PATH"
    )
    config: bpy.props.StringProperty(
        name="Config", description="A train.toml (empty: the defaults)", subtype="FILE_PATH"
    )
    use_frames: bpy.props.BoolProperty(name="Frame range", description="Reconstruct only some frames")
    frame_first: bpy.props.IntProperty(name="First", description="First frame, from 0", min=0)
    frame_end: bpy.props.IntProperty(name="End", description="One past the last frame", min=1, default=1)
    import_result: bpy.props.BoolProperty(
        name="Import result", description="Import OUT/sequence.pc2 when done", default=True
    )
    scene_frame: bpy.props.IntProperty(
        name="Start frame", description="Scene frame showing the result's frame 0", default=1
    )

    def invoke(self, context, event):
        """Starts the job and returns to Blender's event loop, whose timer events drive it.
        (``blender -b`` has no events: it calls ``execute`` instead.)"""
        started = engine.reported(self, lambda: begin(self, context))
        if started is not None:
            return started
        wm = context.window_manager
        self._timer = wm.event_timer_add(POLL_SECONDS, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        """Timer: polls the job (and finishes with it); Esc: cancels it; other events pass."""
        if event.type == "ESC" and event.value == "PRESS":
            engine.reported(self, lambda: cancel(self, context))
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        result = engine.reported(self, lambda: step(self, context))
        if result is None:
            return {"RUNNING_MODAL"}
        context.window_manager.event_timer_remove(self._timer)
        return result

    def execute(self, context):
        """Runs the job to its end without returning to the event loop (scripts, ``blender -b``)."""

        def run():
            begin(self, context)
            return run_to_end(self, context)

        return engine.reported(self, run)
