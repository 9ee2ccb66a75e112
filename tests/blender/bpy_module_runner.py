"""Runs a Blender test script under the `bpy` module (Blender as a Python module, PyPI's `bpy`
wheel) the way ``blender -b`` runs it, so that one script and one command line serve both.

Usage: ``<venv python> bpy_module_runner.py [<file.blend>] [--factory-startup]
[--python-exit-code N] (--python <script> | --python-expr <code>) [-- <args> ...]``, the
arguments of ``blender -b`` that the tests use, with Blender's meaning:

- the .blend file is opened first; --factory-startup loads the factory settings (no user
  preferences or startup file);
- sys.argv looks like Blender's, so scripts read what follows '--';
- an exception escaping the script prints its traceback and exits with N (--python-exit-code;
  without it the process exits 0, as Blender does); otherwise the process exits 0.

A `bpy` module has no window: the scripts that need one (modal operators under Xvfb, the
viewport) run only in the Blender program.
"""

import os
import runpy
import sys
import traceback

USAGE = ("usage: bpy_module_runner.py [<file.blend>] [--factory-startup] "
         "[--python-exit-code N] (--python <script> | --python-expr <code>) [-- <args>]")


def parse(argv):
    """Blender's options as a dict; raises SystemExit with the usage on anything else."""
    options = {"blend": None, "factory": False, "exit_code": 0, "script": None, "expr": None}
    i = 0
    while i < len(argv) and argv[i] != "--":
        arg = argv[i]
        if arg == "--factory-startup":
            options["factory"] = True
        elif arg in ("--python-exit-code", "--python", "--python-expr") and i + 1 < len(argv):
            key = {"--python-exit-code": "exit_code", "--python": "script",
                   "--python-expr": "expr"}[arg]
            options[key] = int(argv[i + 1]) if key == "exit_code" else argv[i + 1]
            i += 1
        elif arg.endswith(".blend") and options["blend"] is None:
            options["blend"] = arg
        else:
            raise SystemExit(f"bpy_module_runner: unknown argument {arg!r}\n{USAGE}")
        i += 1
    if (options["script"] is None) == (options["expr"] is None):
        raise SystemExit(f"bpy_module_runner: give one of --python and --python-expr\n{USAGE}")
    return options


def main():
    options = parse(sys.argv[1:])
    sys.argv = ["blender", "-b", *sys.argv[1:]]
    import bpy
    if options["factory"]:
        bpy.ops.wm.read_factory_settings(use_empty=False)
    if options["blend"]:
        bpy.ops.wm.open_mainfile(filepath=options["blend"], load_ui=False)
    try:
        if options["script"]:
            runpy.run_path(options["script"], run_name="__main__")
        else:
            exec(compile(options["expr"], "<string>", "exec"), {"__name__": "__main__"})
    except SystemExit:
        raise
    except BaseException:  # as Blender: any error of the script becomes the exit code
        traceback.print_exc()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(options["exit_code"])


if __name__ == "__main__":
    main()
