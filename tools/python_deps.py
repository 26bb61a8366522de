"""Checks that the Python modules a turbid tool needs are importable, before it imports them.

The tools start with #!/usr/bin/python3, Debian's Python, where tools/setup installs
python3-matplotlib and python3-numpy. Called as `python3 tools/plot_forces ...` from another Python
(a virtual environment, pyenv) that lacks them, a tool re-runs itself with /usr/bin/python3 when
that one has them, and otherwise says what is missing and how to get it. Standard library only.
"""
import importlib.util
import os
import sys

DEBIAN_PACKAGES = {"numpy": "python3-numpy", "matplotlib": "python3-matplotlib", "scipy": "python3-scipy"}
SYSTEM_PYTHON = "/usr/bin/python3"


def _missing(modules):
    return [m for m in modules if importlib.util.find_spec(m) is None]


def require(*modules):
    missing = _missing(modules)
    if not missing:
        return
    here = os.path.realpath(sys.executable) if sys.executable else ""
    if os.path.exists(SYSTEM_PYTHON) and here != os.path.realpath(SYSTEM_PYTHON) and not os.environ.get("TURBID_PY_REEXEC"):
        # Try Debian's Python, where tools/setup installs them (once: the variable stops a loop).
        probe = "import importlib.util, sys; sys.exit(any(importlib.util.find_spec(m) is None for m in sys.argv[1:]))"
        if os.spawnv(os.P_WAIT, SYSTEM_PYTHON, [SYSTEM_PYTHON, "-c", probe] + missing) == 0:
            os.environ["TURBID_PY_REEXEC"] = "1"
            os.execv(SYSTEM_PYTHON, [SYSTEM_PYTHON, os.path.abspath(sys.argv[0])] + sys.argv[1:])
    tool = os.path.basename(sys.argv[0]) or "this tool"
    packages = " ".join(DEBIAN_PACKAGES.get(m, m) for m in missing)
    sys.exit(
        f"{tool}: this Python ({sys.executable}) has no {', '.join(missing)}. Install them with "
        f"`apt-get install {packages}` (as root; tools/setup does) and run `tools/{tool} ...` directly, "
        f"or `{sys.executable} -m pip install {' '.join(missing)}`."
    )
