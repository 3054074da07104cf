"""Overhead of `tagsplat.track` from Python on a sequence already in memory, against the
engine's own time for the same call, measured side by side in one run. Prints one JSON object.

    .tools/python-venv/bin/python benches/python/track_overhead.py [--frames T] [--side N]
        [--points P] [--repetitions R]

The sequence is a deforming grid of N x N vertices over T frames; the queries are P points near
its frame-0 surface. Each repetition times the whole Python call (argument checks, the copy of
the positions into the engine's per-frame layout, the engine call, the arrays handed back) and
reads the engine call's own time from `Tracks.engine_s`. The target: overhead within 10 %.
"""

import argparse
import datetime
import json
import platform
import statistics
import subprocess
import sys
import time

import numpy as np

import tagsplat


def grid_sequence(side: int, frames: int) -> tagsplat.Sequence:
    """A side x side grid in the xy plane, waving in z from frame to frame."""
    u, v = np.meshgrid(np.linspace(0, 1, side), np.linspace(0, 1, side))
    flat = np.stack([u.ravel(), v.ravel(), np.zeros(side * side)], axis=1)
    t = np.arange(frames)[:, None]
    positions = np.repeat(flat[None], frames, axis=0)
    positions[..., 2] = 0.05 * np.sin(6 * flat[None, :, 0] + 0.3 * t)
    i = np.arange(side - 1)
    a = (i[:, None] * side + i[None, :]).ravel()
    faces = np.concatenate([np.stack([a, a + 1, a + side], 1), np.stack([a + 1, a + side + 1, a + side], 1)])
    return tagsplat.Sequence(faces, positions.astype(np.float32))


def commit() -> str:
    done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    return done.stdout.strip() or "unknown"


def cpu() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=200)
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--points", type=int, default=500)
    parser.add_argument("--repetitions", type=int, default=15)
    args = parser.parse_args()
    seq = grid_sequence(args.side, args.frames)
    rng = np.random.default_rng(0)
    points = np.column_stack([rng.random((args.points, 2)), np.zeros(args.points)])
    tagsplat.track(seq, points=points)  # warm-up
    wall, engine = [], []
    for _ in range(args.repetitions):
        started = time.perf_counter()
        tracks = tagsplat.track(seq, points=points)
        wall.append(time.perf_counter() - started)
        engine.append(tracks.engine_s)
    python_s, engine_s = statistics.median(wall), statistics.median(engine)
    print(json.dumps({
        "command": " ".join([sys.executable, *sys.argv]),
        "commit": commit(),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "device": "none (tracking runs on the host)",
        "host": {"cpu": cpu(), "system": platform.platform(), "python": platform.python_version()},
        "sequence": {"frames": args.frames, "vertices": args.side ** 2, "faces": len(seq.faces)},
        "points": args.points,
        "repetitions": args.repetitions,
        "python_call_s": python_s,
        "engine_call_s": engine_s,
        "overhead_fraction": python_s / engine_s - 1.0,
        "target_fraction": 0.10,
    }, indent=2))


if __name__ == "__main__":
    main()
