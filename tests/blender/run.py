"""Runs the add-on's tests inside Blender:

    blender -b --factory-startup --python tests/blender/run.py -- \
        --package-folder DIR [--cli target/debug/tagsplat] [--work DIR] [-k NAME]

It enables the add-on from tools/blender (``addon_utils``, as Blender's preferences do), points
its preferences at ``--package-folder`` (where the tagsplat wheel is installed), and runs every
``test_*`` function of the ``test_*.py`` modules beside it, each with a fresh work folder and
an empty scene. A test that cannot run (its oracle is missing) prints SKIPPED, and counts as a
failure when CI=true. Blender exits with status 1 when any test fails.
"""

import argparse
import importlib
import os
import shutil
import sys
import tempfile
import time
import traceback

import addon_utils
import bpy

# No __pycache__ folders in the source tree from a test run.
sys.dont_write_bytecode = True

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
ADDON = "tagsplat_blender"


class Skipped(Exception):
    """Raised by a test whose oracle or tool is missing; the message says which."""


class Env:
    """What a test is given: the options, its own empty work folder, and ``skip``."""

    def __init__(self, options, work):
        self.cli = options.cli
        self.package_folder = options.package_folder
        self.work = work

    def skip(self, reason):
        """Stops the test as SKIPPED for ``reason``."""
        raise Skipped(reason)

    def require_cli(self):
        """The tagsplat program's path, or SKIPPED when it was not given or does not exist."""
        if not self.cli or not os.access(self.cli, os.X_OK):
            self.skip(f"the tagsplat program ({self.cli or 'no --cli'}) is missing")
        return self.cli


def parse():
    """The options after Blender's ``--``."""
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="tests/blender/run.py")
    parser.add_argument("--package-folder", default="", help="folder holding the tagsplat package")
    parser.add_argument("--cli", default="", help="the tagsplat program (synthetic data)")
    parser.add_argument(
        "--work", default="", help="work folder, kept (default: a temporary one, removed after a clean run)"
    )
    parser.add_argument("-k", default="", help="run only tests whose name contains this")
    return parser.parse_args(argv)


def enable_addon(package_folder):
    """Enables the add-on from tools/blender and sets its package folder; fails loudly."""
    sys.path.insert(0, os.path.join(ROOT, "tools", "blender"))
    module = addon_utils.enable(ADDON, default_set=True, handle_error=None)
    assert module is not None, f"{ADDON} did not enable"
    bpy.context.preferences.addons[ADDON].preferences.package_folder = package_folder
    bpy.context.preferences.addons[ADDON].preferences.validation = (
        os.environ.get("TAGSPLAT_VALIDATION") == "1"
    )


def empty_scene():
    """A new, unsaved, empty file (the add-on and its preferences stay): each test starts
    from nothing."""
    bpy.ops.wm.read_homefile(use_empty=True)
    assert not bpy.data.objects and not bpy.data.filepath


def tests(name_filter):
    """(name, function) of every test function in the test modules, in file order."""
    sys.path.insert(0, HERE)
    found = []
    for file in sorted(os.listdir(HERE)):
        if file.startswith("test_") and file.endswith(".py"):
            module = importlib.import_module(file[:-3])
            for name, value in vars(module).items():
                full = f"{file[:-3]}.{name}"
                if name.startswith("test_") and callable(value) and name_filter in full:
                    found.append((full, value))
    return found


def run_one(name, test, options, root):
    """Runs one test; returns 'PASS', 'FAIL' or 'SKIPPED' and prints the outcome."""
    work = os.path.join(root, name)
    os.makedirs(work)
    empty_scene()
    start = time.monotonic()
    try:
        test(Env(options, work))
        outcome = "PASS"
    except Skipped as e:
        outcome = "SKIPPED"
        print(f"SKIPPED {name}: {e}")
    except Exception:
        outcome = "FAIL"
        traceback.print_exc()
    print(f"{outcome} {name} ({time.monotonic() - start:.1f} s)", flush=True)
    return outcome


def check_validation():
    """'FAIL' when a GPU context the tests opened logged a validation message, else 'PASS'."""
    from tagsplat_blender import engine

    messages = [m for ctx in engine._contexts.values() for m in ctx.validation_messages()]
    for message in messages:
        print(f"validation: {message}")
    outcome = "FAIL" if messages else "PASS"
    print(f"{outcome} Vulkan validation ({len(messages)} messages)", flush=True)
    return outcome


def main():
    """Runs the tests and exits Blender with 0 when all passed (SKIPPED fails under CI=true)."""
    options = parse()
    enable_addon(options.package_folder)
    root = options.work or tempfile.mkdtemp(prefix="tagsplat-blender-")
    shutil.rmtree(root, ignore_errors=True)
    outcomes = [run_one(name, test, options, root) for name, test in tests(options.k)]
    if not outcomes:
        print(f"no test matches -k {options.k!r}", flush=True)
        sys.exit(1)
    outcomes.append(check_validation())
    failed = outcomes.count("FAIL") + (outcomes.count("SKIPPED") if os.environ.get("CI") == "true" else 0)
    print(f"{outcomes.count('PASS')} passed, {outcomes.count('FAIL')} failed, "
          f"{outcomes.count('SKIPPED')} skipped", flush=True)
    if not failed and not options.work:
        shutil.rmtree(root)
    sys.exit(1 if failed else 0)


main()
