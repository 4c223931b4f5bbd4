#!/usr/bin/env python3
"""Impact force of granular_impact_3d runs at several slopes (Trujillo-Vela et al. 2020 section 5.3, Fig. 14-15).

usage: plot_impact.py OUT.png RUN_DIR [RUN_DIR ...] [--peaks "LABEL=SLOPE:N,SLOPE:N,..."]...

Each RUN_DIR is the output of `lahar check` on cases/granular_impact_3d.yaml (any slope, any dx):
the script reads only its check.json (reference granular_impact), so the force history it draws is
the check's own (the wall's force along the chute, 10 ms moving average; coordinator/check/check_soil_impact.c),
and prints a Markdown table: slope, dx, first impact, peak force and its time, the momentum flux
estimate rho u^2 A, and the run's metrics. Left panel: F(t) per slope; right panel: peak force
against the slope. Trujillo-Vela et al. 2020, Fig. 14-15, are images whose numbers are not in the paper's text
(shared/papers/000), so no published curve is drawn. --peaks (repeatable) adds a series of peak
forces from elsewhere to the right panel, e.g. the same case at another dx whose run directories
are gone: --peaks "dx 25 mm=45:366,50:433,55:570,60:824,65:928"."""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("matplotlib")
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def fail(msg):
    print("plot_impact: " + msg, file=sys.stderr)
    sys.exit(2)


def load(run):
    try:
        with open(os.path.join(run, "check.json")) as f:
            chk = json.load(f)
    except (OSError, ValueError) as e:
        fail("%s: no readable check.json (%s)" % (run, e))
    if chk.get("reference") != "granular_impact" or "info" not in chk:
        fail("%s: not a finished granular_impact check (reference %r)" % (run, chk.get("reference")))
    info = dict(chk["info"])
    info.update({k: v["value"] for k, v in chk["metrics"].items()})
    curve = chk["plot"]["panels"][0]["curves"][0]
    return chk, info, curve


def parse_peaks(text):
    """'LABEL=S:F,S:F' -> (label, [slopes], [forces])."""
    label, sep, pairs = text.rpartition("=")
    try:
        pts = sorted(tuple(float(v) for v in p.split(":")) for p in pairs.split(","))
        if not sep or not label or any(len(p) != 2 for p in pts):
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError("expected LABEL=SLOPE:N,SLOPE:N,... (got %r)" % text)
    return label, [p[0] for p in pts], [p[1] for p in pts]


def main(argv):
    ap = argparse.ArgumentParser(prog="plot_impact.py", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="the PNG to write")
    ap.add_argument("runs", nargs="+", help="output directories of lahar check on granular_impact_3d")
    ap.add_argument("--peaks", type=parse_peaks, action="append", default=[],
                    help="LABEL=SLOPE:N,... a further series of peak forces for the right panel")
    args = ap.parse_args(argv[1:])
    runs = []
    for run in args.runs:
        chk, info, curve = load(run)
        runs.append((info["slope_deg"], run, chk, info, curve))
    runs.sort(key=lambda r: r[0])
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5))
    print("| slope | dx [m] | first impact [s] | peak F [N] (10 ms) | at [s] | raw peak [N] | rho u^2 A [N] "
          "| M g sin(theta) [N] | escaped | momentum balance (rel.) | pass |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for slope, run, chk, info, curve in runs:
        dx = info.get("dx_m", float("nan"))
        ax.plot(curve["x"], curve["y"], lw=1, label="%.0f deg" % slope)
        first = info["first_impact_s"]  # None: the soil never reached the wall in the run
        print("| %.0f° | %s | %s | %.0f | %.3f | %.0f | %.0f | %.0f | %d | %.1e | %s |" % (
            slope, "%.4g" % dx, "none" if first is None else "%.3f" % first, info["peak_force_N"], info["peak_time_s"],
            info["peak_force_raw_N"], info["momentum_flux_max_N"], info["weight_along_chute_N"],
            info["escaped_particles"], info["momentum_balance_rel_error"], "yes" if chk["pass"] else "no"))
    ax.set_xlabel("t (s)")
    ax.set_ylabel("impact force on the wall F (N)")
    ax.set_title("wall force along the chute (10 ms moving average)")
    ax.legend()
    ax.grid(alpha=0.3)
    s = [r[0] for r in runs]
    dxs = sorted({r[3].get("dx_m") for r in runs if isinstance(r[3].get("dx_m"), (int, float))})
    bx.plot(s, [r[3]["peak_force_N"] for r in runs], "o-", label="lahar peak (10 ms average)" +
            (", dx %g mm" % (1e3 * dxs[0]) if len(dxs) == 1 else ""))
    for label, ps, fs in args.peaks:
        bx.plot(ps, fs, "^-.", label=label)
    bx.plot(s, [r[3]["momentum_flux_max_N"] for r in runs], "s--", label="rho u^2 A of the arriving soil")
    bx.plot(s, [r[3]["weight_along_chute_N"] for r in runs], ":", label="M g sin(theta)")
    bx.set_xlabel("slope (deg)")
    bx.set_ylabel("force (N)")
    bx.set_title("peak force per slope (Trujillo-Vela et al. 2020 Fig. 15: no numbers in its text)", fontsize=10)
    bx.legend()
    bx.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
