"""Shared start-up for lahar's python tools: make sure h5py/numpy (and matplotlib when asked)
import. Debian installs them for /usr/bin/python3 (python3-h5py, python3-matplotlib); when the
`python3` first on PATH is another interpreter (pyenv, venv) without them, re-run the script under
/usr/bin/python3 once instead of failing."""
import importlib
import os
import sys

SYSTEM_PYTHON = "/usr/bin/python3"


def require(*modules):
    """Import `modules` or re-exec under Debian's python3; exit 3 with a message if impossible."""
    missing = []
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    if not missing:
        return
    if (os.path.exists(SYSTEM_PYTHON) and os.path.realpath(sys.executable) != os.path.realpath(SYSTEM_PYTHON)
            and not os.environ.get("LAHAR_PY_REEXEC")):
        os.environ["LAHAR_PY_REEXEC"] = "1"
        os.execv(SYSTEM_PYTHON, [SYSTEM_PYTHON] + sys.argv)
    pkgs = " ".join("python3-" + m for m in missing)
    sys.stderr.write(f"{os.path.basename(sys.argv[0])}: python modules missing: {', '.join(missing)} "
                     f"(apt-get install {pkgs})\n")
    sys.exit(3)


def window_mean_peak(t, p, t0, tau, span):
    """Largest mean of p over a window of length tau, (1/tau) int_s^{s+tau} p dt (trapezoids), for
    window starts s at the samples in [t0 - tau, t0 + span]: a peak as a sensor of response time
    tau reads it. nan when the series is shorter than tau or has no start there."""
    import numpy as np
    c = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))])
    starts = t[(t >= t0 - tau) & (t <= t0 + span)]
    if len(starts) == 0 or t[-1] - t[0] < tau:
        return float("nan")
    best = -np.inf
    for s in starts:
        if s + tau > t[-1]:
            break
        best = max(best, (np.interp(s + tau, t, c) - np.interp(s, t, c)) / tau)
    return float(best)


def _finite_or_none(x):
    import math
    if isinstance(x, dict):
        return {k: _finite_or_none(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite_or_none(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def dump_json(obj, fh):
    """obj as strict JSON (jq, JavaScript and other parsers reject NaN and Infinity): a quantity
    with no value (a run without an impact, a ratio over zero) is written as null."""
    import json
    json.dump(_finite_or_none(obj), fh, indent=1, allow_nan=False)


def null_as_nan(d):
    """json.load(..., object_hook=null_as_nan): the nulls dump_json wrote read back as nan, so
    that arithmetic and formatting on a quantity with no value give nan instead of a TypeError."""
    return {k: float("nan") if v is None else v for k, v in d.items()}


def run_case(out):
    """The case file a run in directory `out` was made from (OUT/summary.json "case"). Exit 2 with
    what to do when there is no summary or the run has not ended (lahar writes the case's path
    when it stops; a killed run leaves status "running")."""
    import json
    tool = os.path.basename(sys.argv[0])
    path = os.path.join(out, "summary.json")
    try:
        with open(path) as fh:
            summary = json.load(fh)
    except (OSError, ValueError) as exc:
        sys.stderr.write(f"{tool}: {path}: {exc}; give the output directory of a lahar run (lahar run CASE -o OUT)\n")
        sys.exit(2)
    if "case" not in summary:
        sys.stderr.write(f"{tool}: {path}: status {summary.get('status', '?')}: {summary.get('message', '')}; "
                         f"wait for the run to end, or continue it with `lahar resume {out}`\n")
        sys.exit(2)
    return summary["case"]
