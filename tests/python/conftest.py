"""Shared fixtures: the `tagsplat` program the tests compare against, a tiny generated dataset,
one context for the session (its validation messages fail the session), and the quick training
config of tests/pipeline.rs as a dict and as TOML."""

import os
import pathlib
import subprocess

import pytest

import tagsplat

ROOT = pathlib.Path(__file__).resolve().parents[2]

# tests/pipeline.rs's quick_config: few iterations, SH degree 0.
QUICK_CONFIG = {
    "sh_degree": 0,
    "canonical": {"iterations": 80, "densify_from": 20, "densify_until": 60, "densify_every": 20},
    "temporal": {"iterations": 100},
    "report": {"stats_every": 10},
}


def toml_of(config: dict) -> str:
    """`config` (one level of tables) as TOML text."""
    top = [f"{k} = {v!r}" for k, v in config.items() if not isinstance(v, dict)]
    tables = [
        f"[{k}]\n" + "\n".join(f"{kk} = {vv!r}" for kk, vv in v.items())
        for k, v in config.items()
        if isinstance(v, dict)
    ]
    return "\n".join(top) + "\n\n" + "\n\n".join(tables) + "\n"


def missing_oracle(what: str) -> None:
    """An oracle the test needs is absent: SKIPPED, or a failure when CI=true."""
    if os.environ.get("CI") == "true":
        pytest.fail(f"oracle missing under CI: {what}")
    pytest.skip(f"SKIPPED: {what}")


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The `tagsplat` program built with the wheel (`cargo build --profile test --bin tagsplat`)."""
    path = pathlib.Path(os.environ.get("TAGSPLAT_CLI", ROOT / "target" / "debug" / "tagsplat"))
    if not path.is_file():
        missing_oracle(f"{path} (cargo build --profile test --bin tagsplat)")
    return path


def run_cli(cli: pathlib.Path, *args: object) -> str:
    """Runs the program; its stdout. A failure shows its stderr."""
    done = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, f"tagsplat {args}: {done.stderr}"
    return done.stdout


@pytest.fixture(scope="session")
def data(cli: pathlib.Path, tmp_path_factory: pytest.TempPathFactory) -> pathlib.Path:
    """tests/pipeline.rs's sequence: 8 views at 96², three frames, by `tagsplat synth`."""
    out = tmp_path_factory.mktemp("synth") / "data"
    run_cli(cli, "synth", "--out", out, "--subdivisions", 3, "--views", 8, "--frames", 3,
            "--resolution", 96, "--seed", 5, "--samples", 2, "--track-vertices", 100,
            "--track-surface", 200)
    return out


@pytest.fixture(scope="session")
def ctx():
    """One context for the session; any validation message fails it at the end."""
    context = tagsplat.Context()
    yield context
    assert context.validation_messages() == []


@pytest.fixture(scope="session")
def quick_toml(tmp_path_factory: pytest.TempPathFactory) -> pathlib.Path:
    """QUICK_CONFIG as a TOML file, for the program."""
    path = tmp_path_factory.mktemp("config") / "quick.toml"
    path.write_text(toml_of(QUICK_CONFIG))
    return path


@pytest.fixture(scope="session")
def cli_train(cli, data, quick_toml, tmp_path_factory) -> pathlib.Path:
    """The program's run of frames 0..2 with the quick config: the bytes to match."""
    out = tmp_path_factory.mktemp("cli") / "out"
    run_cli(cli, "train", "--data", data, "--out", out, "--config", quick_toml, "--frames", "0..2")
    return out


def output_bytes(out: pathlib.Path) -> dict[str, bytes]:
    """The meshes and sequence exports of a training run, by relative path."""
    files = sorted(out.glob("meshes/*")) + sorted(out.glob("sequence.*"))
    assert files, f"no meshes in {out}"
    return {str(f.relative_to(out)): f.read_bytes() for f in files}
