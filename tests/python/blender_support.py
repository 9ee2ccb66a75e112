"""Running Debian's Blender from tests, whichever Python runs pytest.

Debian's Blender embeds the system Python 3.11 but picks its Python home from the first python3
on PATH: under the pyenv interpreter that is pyenv's, and Blender then loses Debian's
site-packages (numpy). run_blender therefore drops pyenv's folders from PATH.
"""

import os
import shutil
import subprocess

BLENDER = shutil.which("blender")


def blender_env():
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join(
        p for p in env.get("PATH", "").split(os.pathsep) if ".pyenv" not in p)
    return env


def run_blender(script, *args, timeout=600):
    """Runs `blender -b --factory-startup --python-exit-code 1 --python script -- args`."""
    command = [BLENDER, "-b", "--factory-startup", "--python-exit-code", "1",
               "--python", str(script)]
    if args:
        command += ["--", *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                          env=blender_env())
