"""Code lahar's python tools share.

Start-up (require): make sure h5py/numpy (and matplotlib when asked) import. Debian installs them
for /usr/bin/python3 (python3-h5py, python3-matplotlib); when the `python3` first on PATH is
another interpreter (pyenv, venv) without them, re-run the script under /usr/bin/python3 once
instead of failing. Then: a sensor's window mean, strict JSON out and in, a run's case, a body's
force stream, the command line and verdict of the comparison tools, Richardson extrapolation, and
the command line, input, dx axis and PNG of the convergence plots."""
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


def text_names(raw):
    """Names stored as an HDF5 string array (forces.h5 body_names, bodies.h5 header/body_name) as str."""
    return [n.decode() if isinstance(n, bytes) else str(n) for n in raw]


class InputError(Exception):
    """A run or case a tool cannot read; the message says what is missing and what to do."""


def body_force(out, body, option):
    """(t, force rows [n, 3]) of the body named `body` in OUT/forces.h5; InputError naming the
    file, the bodies it holds and the `option` that chooses another."""
    import h5py
    path = os.path.join(out, "forces.h5")
    try:
        with h5py.File(path, "r") as f:
            names = text_names(f.attrs.get("body_names", []))
            if body not in names:
                raise InputError(f"{path}: no body '{body}' (bodies: {', '.join(names)}); give it with {option}")
            t = f["t"][()]
            return t, f["force"][: len(t), names.index(body), :]
    except OSError as e:
        raise InputError(f"{path}: {e}")


def compare_cli(ap, name):
    """The arguments compare_bore.py and compare_jet.py share: the run, the PNG, the JSON (default
    OUT/NAME.png, OUT/NAME.json), --no-plot and --check."""
    ap.add_argument("out", help="run output directory")
    ap.add_argument("-o", "--output", help=f"PNG (default OUT/{name}.png)")
    ap.add_argument("--json", help=f"metrics as JSON (default OUT/{name}.json)")
    ap.add_argument("--no-plot", action="store_true", help="write no PNG")
    ap.add_argument("--check", action="store_true", help="exit 1 when a bound below is not met")


def check_verdict(tool, failures):
    """Print one `TOOL: FAIL ...` line per failed bound; the exit status of --check (1 if any)."""
    for x in failures:
        print(f"{tool}: FAIL {x}")
    return 1 if failures else 0


def running_mean(t, p, tau):
    """p averaged over a centred window of tau (samples assumed about evenly spaced); within tau/2
    of either end over the samples the window holds there."""
    import numpy as np
    w = max(1, int(round(tau / np.median(np.diff(t))))) if len(t) > 1 else 1
    mean = np.convolve(p, np.ones(w) / w, mode="same")
    held = np.convolve(np.ones(len(p)), np.ones(w), mode="same")  # samples in each window
    edge = held < w
    mean[edge] *= w / held[edge]
    return mean


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


def richardson_order(dxs, r_obs, lo=0.25, hi=4.0):
    """The order p of error ~ C dx^p that three resolutions dx1 > dx2 > dx3 with solution
    differences |q1 - q2| / |q2 - q3| = r_obs imply: (dx1^p - dx2^p) / (dx2^p - dx3^p) = r_obs,
    solved by bisection (the left side grows with p). None when r_obs lies outside what orders in
    [lo, hi] give (the runs do not converge monotonically)."""
    import math
    d1, d2, d3 = dxs

    def g(p):
        return (d1 ** p - d2 ** p) / (d2 ** p - d3 ** p)
    if not (math.isfinite(r_obs) and g(lo) <= r_obs <= g(hi)):
        return None
    a, b = lo, hi
    for _ in range(200):
        m = 0.5 * (a + b)
        if g(m) < r_obs:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


def richardson_extrapolate(dxs, qs):
    """The converged value of a scalar q from runs at three resolutions dx1 > dx2 > dx3 (any
    refinement ratios): q* = q3 + (q3 - q2) dx3^p / (dx2^p - dx3^p) with the observed order p of
    richardson_order (Roache 1998; Celik et al. 2008). Returns (q*, p), or None when the three do
    not converge monotonically: the differences change sign, one is zero, or no order in
    [0.25, 4] fits their ratio. Then no converged value can be read off the runs."""
    return richardson_extrapolate_or_why(dxs, qs)[0]


def richardson_extrapolate_or_why(dxs, qs):
    """richardson_extrapolate's result and, when it is None, why as a short phrase: "no value in a
    run", "dx not decreasing", "not monotone" (the differences change sign or one is zero), "no
    order in 0.25-4 (difference ratio r)" (they shrink too slowly or too fast)."""
    import math
    (d1, d2, d3), (q1, q2, q3) = dxs, qs
    if not all(math.isfinite(q) for q in qs):
        return None, "no value in a run"
    if not d1 > d2 > d3 > 0:
        return None, "dx not decreasing"
    e12, e23 = q1 - q2, q2 - q3
    if e12 * e23 <= 0:
        return None, "not monotone"
    p = richardson_order((d1, d2, d3), e12 / e23)
    if p is None:
        return None, "no order in 0.25-4 (difference ratio %.3g)" % (e12 / e23)
    return (q3 + (q3 - q2) * d3 ** p / (d2 ** p - d3 ** p), p), None


def convergence_args(doc, load, fail):
    """The command line of a convergence plot, `TOOL OUT.png "LABEL=RUN[,RUN...]" ...`: returns the
    PNG's path and the series [(label, [m, ...])] with m = load(RUN) (a dict with the run's "dx"),
    each series ordered coarse to fine. Prints `doc` and exits 0 on -h/--help, 2 on too few
    arguments; fail(msg) on a PNG that is not one or whose directory is missing, and on an
    argument that is not LABEL=RUN[,RUN...]."""
    args = sys.argv[1:]
    if len(args) < 2 or args[0] in ("-h", "--help"):
        print(doc)
        sys.exit(0 if args and args[0] in ("-h", "--help") else 2)
    png = args[0]
    if not png.endswith(".png"):
        fail("the first argument is the PNG to write (got %r)" % png)
    if not os.path.isdir(os.path.dirname(os.path.abspath(png))):
        fail("%s: its directory does not exist; create it or write the PNG elsewhere" % png)
    series = []
    for spec in args[1:]:
        label, eq, runs = spec.partition("=")
        paths = [r for r in runs.split(",") if r]
        if not eq or not label or not paths:
            fail("%r: expected LABEL=RUN[,RUN...]" % spec)
        series.append((label, sorted((load(r) for r in paths), key=lambda m: -m["dx"])))
    return png, series


def read_compare_json(run, name, compare_tool, fail):
    """(path, metrics) of the JSON `name` a compare tool wrote into run directory `run` (or `run`
    itself when it is a .json file), nulls read as nan; fail(msg) saying to run `compare_tool` on
    it when it cannot be read."""
    import json
    path = run if run.endswith(".json") else os.path.join(run, name)
    try:
        with open(path) as f:
            return path, json.load(f, object_hook=null_as_nan)
    except (OSError, ValueError) as e:
        fail("%s: no readable %s (%s); run tools/%s on it first" % (run, name, e, compare_tool))


def fail_usage(msg):
    """A tool's error on bad usage or input: its name and msg on stderr, exit 2."""
    sys.stderr.write("%s: %s\n" % (os.path.splitext(os.path.basename(sys.argv[0]))[0], msg))
    sys.exit(2)


def save_png(fig, png, fail):
    """Write the figure (fail(msg) when it cannot be) and say where."""
    try:
        fig.savefig(png, dpi=90)
    except OSError as e:
        fail("%s: cannot write it (%s)" % (png, e))
    print("wrote", png)


def dx_axis(ax, dxs):
    """A logarithmic dx axis (mm) for a convergence plot: finer to the right, ticks at the runs' dx
    `dxs` instead of decades."""
    from matplotlib.ticker import NullFormatter
    ticks = sorted(set(dxs))
    ax.set_xscale("log")
    ax.set_xlim(max(ticks) * 1.3, min(ticks) / 1.3)
    ax.set_xticks(ticks, ["%g" % d for d in ticks])
    ax.xaxis.set_minor_formatter(NullFormatter())


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
