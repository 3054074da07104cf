"""The reconstruction operator on a tiny synthetic dataset (``tagsplat synth``): driven through
its modal() as Blender's timer and Esc would drive it, it trains, reports progress, imports
OUT/sequence.pc2 (Blender's evaluated mesh = the file's numbers), and Esc cancels it.

``blender -b`` has no window, so no timer event reaches a modal operator; the tests deliver
the events themselves to the operator's own modal(), with a stand-in for the operator instance
(Blender makes real ones only for an operator it calls)."""

import os
import subprocess
import time
from collections import namedtuple

import bpy
import numpy as np

import oracle
from tagsplat_blender import train

Event = namedtuple("Event", "type value")
TIMER, ESC, MOUSE = Event("TIMER", "NOTHING"), Event("ESC", "PRESS"), Event("MOUSEMOVE", "NOTHING")

# Smaller than tests/pipeline.rs's quick_config: about 15 s for two frames on lavapipe.
QUICK = """sh_degree = 0
[canonical]
iterations = {iterations}
densify_from = 5
densify_until = 15
densify_every = 5
[temporal]
iterations = 20
min_iterations = 10
colour_iterations = 4
[temporal.graph]
iterations = 20
min_iterations = 10
[report]
stats_every = 5
"""


class Driven:
    """Stands in for the operator instance: the operator's properties, its timer, and the
    reports it makes."""

    def __init__(self, **properties):
        self.__dict__.update(properties)
        self._timer = bpy.context.window_manager.event_timer_add(train.POLL_SECONDS)
        self.reports = []

    def report(self, kinds, message):
        """Keeps a report as Operator.report would show it."""
        self.reports.append((set(kinds), message))


def dataset(env):
    """A 2-frame, 6-view, 64² synthetic dataset made by the tagsplat program; its folder."""
    data = os.path.join(env.work, "data")
    subprocess.run(
        [env.require_cli(), "synth", "--out", data, "--subdivisions", "2", "--views", "6",
         "--frames", "2", "--resolution", "64", "--samples", "1", "--seed", "5"],
        check=True, stdout=subprocess.DEVNULL,
    )
    return data


def driven(env, data, out, iterations):
    """A started job (the operator's begin) with the quick config at ``iterations``."""
    config = os.path.join(env.work, f"quick{iterations}.toml")
    with open(config, "w") as f:
        f.write(QUICK.format(iterations=iterations))
    op = Driven(data=data, out=out, config=config, use_frames=False, frame_first=0, frame_end=1,
                import_result=True, scene_frame=1)
    train.begin(op, bpy.context)
    return op


def drive(op, until, event=TIMER, seconds=300):
    """Delivers ``event`` to the operator's modal() every poll interval until ``until(result)``;
    returns the last result."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        result = train.TAGSPLAT_OT_train.modal(op, bpy.context, event)
        if until(result):
            return result
        time.sleep(train.POLL_SECONDS)
    raise AssertionError(f"the job did not get there in {seconds} s; reports {op.reports}")


def test_a_modal_reconstruction_reports_progress_and_imports_its_sequence(env):
    data = dataset(env)
    out = os.path.join(env.work, "out")
    op = driven(env, data, out, iterations=20)
    assert train.TAGSPLAT_OT_train.modal(op, bpy.context, MOUSE) == {"PASS_THROUGH"}
    seen = []
    result = drive(op, lambda r: seen.append(op._run["latest"]) or r != {"RUNNING_MODAL"})
    assert result == {"FINISHED"}, op.reports
    iterations = [p.iteration for p in seen if p is not None]
    assert iterations and max(iterations) > 0, "progress was shown"
    pc2 = os.path.join(out, "sequence.pc2")
    (obj,) = bpy.data.objects
    assert bpy.path.abspath(obj.modifiers[0].filepath) == pc2, "OUT's own .pc2, no copy"
    expected = oracle.read_pc2(pc2)
    assert len(expected) == 2
    for t in range(2):
        np.testing.assert_array_equal(oracle.evaluated_positions(bpy, obj, 1 + t), expected[t])
    assert any("reconstructed" in message for _, message in op.reports)


def test_esc_cancels_a_run_and_a_second_run_into_its_output_is_refused(env):
    data = dataset(env)
    out = os.path.join(env.work, "out")
    op = driven(env, data, out, iterations=100000)
    drive(op, lambda r: op._run["latest"] is not None and op._run["latest"].iteration > 0)
    try:
        bpy.ops.tagsplat.train(data=data, out=out)
        raise AssertionError("a second run into the same output was started")
    except RuntimeError as e:
        assert out in str(e), str(e)
    assert train.TAGSPLAT_OT_train.modal(op, bpy.context, ESC) == {"RUNNING_MODAL"}
    assert op._run["cancelling"]
    result = drive(op, lambda r: r != {"RUNNING_MODAL"}, seconds=60)
    assert result == {"CANCELLED"}
    assert [k for k, m in op.reports if "cancelled" in m] == [{"WARNING"}], op.reports
    assert not bpy.data.objects, "nothing imported"


def expect_error(words, **settings):
    """The train operator fails with an error report containing every one of ``words``."""
    try:
        bpy.ops.tagsplat.train(**settings)
    except RuntimeError as e:
        assert all(w in str(e) for w in words), str(e)
        return
    raise AssertionError(f"no error for {settings}")


def test_a_missing_dataset_or_folder_is_reported_by_name(env):
    missing = os.path.join(env.work, "no-such-data")
    expect_error([missing], data=missing, out=os.path.join(env.work, "out"))
    expect_error(["no output folder chosen"], data=missing)
