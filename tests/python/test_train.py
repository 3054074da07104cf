"""Training through Python: byte-identical meshes to the program's run, cancelling (by the
callback, by the job object, by Ctrl-C) and resuming, callbacks that raise, and a second job
into an output folder in use."""

import os
import signal
import threading
import time

import pytest

import tagsplat
from conftest import QUICK_CONFIG, output_bytes


def test_train_writes_the_programs_bytes(ctx, data, cli_train, quick_toml, tmp_path):
    seen = []
    report = tagsplat.train(ctx, data, tmp_path / "out", config=QUICK_CONFIG, frames=range(0, 2),
                            progress=seen.append)
    assert [f["frame"] for f in report["frames"]] == [0, 1]
    assert output_bytes(tmp_path / "out") == output_bytes(cli_train)
    # The callback saw the frames' iterations count up, with a loss and the time.
    frames = [p for p in seen if p.stage == "frame"]
    assert {p.frame for p in frames} == {0, 1} and all(p.frames_end == 2 for p in frames)
    assert any(p.loss is not None for p in frames)
    assert [p.update for p in seen] == sorted(set(p.update for p in seen))
    # A TOML path gives the same run; the finished frames are resumed, not redone.
    again = tagsplat.train(ctx, data, tmp_path / "out", config=quick_toml, frames=(0, 2))
    assert again["resumed_frames"] == [0, 1]


def test_a_cancelled_run_stops_within_an_iteration_and_resumes_to_the_same_bytes(
        ctx, data, cli_train, tmp_path):
    out = tmp_path / "out"
    stamps = {}

    def stop_in_frame_1(p):
        stamps.setdefault("last", []).append(time.monotonic())
        if p.stage == "frame" and p.frame == 1 and p.iteration >= 20:
            stamps["cancelled"] = time.monotonic()
            return False
        return True

    with pytest.raises(tagsplat.CancelledError):
        tagsplat.train(ctx, data, out, config=QUICK_CONFIG, frames=(0, 2), progress=stop_in_frame_1)
    returned = time.monotonic() - stamps["cancelled"]
    gaps = [b - a for a, b in zip(stamps["last"][-20:], stamps["last"][-19:])]
    assert returned < max(gaps) + 1.0, f"returned {returned:.2f} s after the cancel"
    report = tagsplat.train(ctx, data, out, config=QUICK_CONFIG, frames=(0, 2))
    assert report["resumed_frames"] == [0]
    assert output_bytes(out) == output_bytes(cli_train)


def test_a_job_object_is_polled_and_cancelled(ctx, data, tmp_path):
    job = tagsplat.start_train(ctx, data, tmp_path / "out", config=QUICK_CONFIG, frames=(0, 1))
    while (p := job.poll()) is None or p.stage != "frame":
        assert not job.done
        time.sleep(0.05)
    assert p.iteration >= 1 and p.elapsed_s > 0
    job.cancel()
    with pytest.raises(tagsplat.CancelledError):
        job.wait(timeout=60)
    assert job.done and job.poll() is None
    with pytest.raises(tagsplat.CancelledError):
        job.wait()


def test_a_callback_that_raises_stops_the_job_with_its_exception(ctx, data, tmp_path):
    class Boom(Exception):
        pass

    def boom(p):
        if p.stage == "frame":
            raise Boom("from the callback")

    with pytest.raises(Boom, match="from the callback"):
        tagsplat.train(ctx, data, tmp_path / "out", config=QUICK_CONFIG, frames=(0, 1), progress=boom)
    # The job has stopped and released OUT: a new run there starts (and is cancelled at once).
    with pytest.raises(tagsplat.CancelledError):
        tagsplat.train(ctx, data, tmp_path / "out", config=QUICK_CONFIG, frames=(0, 1),
                       progress=lambda p: False)


def test_ctrl_c_cancels_the_run_then_raises_keyboard_interrupt(ctx, data, tmp_path):
    # A run far longer than the signal can take to arrive, even on a loaded host (the quick one
    # could end first); the callback ends it after a minute, so a Ctrl-C that is missed fails
    # the test (CancelledError) instead of hanging it.
    endless = {**QUICK_CONFIG, "canonical": {**QUICK_CONFIG["canonical"], "iterations": 1_000_000}}
    started = threading.Event()
    first_progress = []

    def watch(p):
        # Any progress means the run is under way (this one never leaves its canonical stage);
        # the minute counts from there, since setting up can itself take a minute on a busy host.
        started.set()
        first_progress.append(time.monotonic())
        return time.monotonic() - first_progress[0] < 60

    timer = threading.Thread(target=lambda: started.wait(120) and os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        tagsplat.train(ctx, data, tmp_path / "out", config=endless, frames=(0, 1), progress=watch)
    timer.join()


def test_a_second_job_into_one_output_is_refused(ctx, data, tmp_path):
    out = tmp_path / "out"
    first = tagsplat.start_train(ctx, data, out, config=QUICK_CONFIG, frames=(0, 1))
    while first.progress.update == 0:
        time.sleep(0.05)
    with pytest.raises(tagsplat.Error, match=str(out)):
        tagsplat.train(ctx, data, out, config=QUICK_CONFIG, frames=(0, 1))
    first.cancel()
    with pytest.raises(tagsplat.CancelledError):
        first.wait()


def test_bad_training_arguments_are_refused_by_name(ctx, data, tmp_path):
    out = tmp_path / "out"
    with pytest.raises(tagsplat.BadInputError, match="frames: '2..1' is empty"):
        tagsplat.start_train(ctx, data, out, frames=(2, 1))
    with pytest.raises(tagsplat.BadInputError, match="unknown field"):
        tagsplat.start_train(ctx, data, out, config={"no_such_key": 1})
    with pytest.raises(tagsplat.BadInputError, match="report.stats_every"):
        tagsplat.start_train(ctx, data, out, config={"report": {"stats_every": 0}})
    with pytest.raises(tagsplat.BadInputError, match="fps"):
        tagsplat.start_train(ctx, data, out, fps=-1.0)
    with pytest.raises(tagsplat.BadInputError, match="up: 'x'"):
        tagsplat.start_train(ctx, data, out, up="x")
    with pytest.raises(tagsplat.Error, match="no_such_data"):
        tagsplat.train(ctx, tmp_path / "no_such_data", out, config=QUICK_CONFIG)
