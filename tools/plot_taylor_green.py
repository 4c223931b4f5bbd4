#!/usr/bin/env python3
"""E(t)/E0 of Taylor-Green runs against the exact exp(-16 pi^2 nu t / L^2), one curve per run.

  tools/plot_taylor_green.py OUT.png LABEL=RUN_DIR [LABEL=RUN_DIR ...]

RUN_DIR is the output of `lahar check` on cases/taylor_green_2d.yaml (or a variant): its
check.json holds the measured E/E0 and the exact curve (coordinator/check/check_fluid_internal.c, taylor_green)."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("matplotlib")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) > 1 and argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    exact = None
    for arg in argv[2:]:
        label, run = arg.split("=", 1)
        with open(run + "/check.json") as f:
            d = json.load(f)
        p = d["plot"]
        err = d["metrics"]["energy_decay_rel_error"]["value"]
        ax.semilogy(p["t"], p["measured"], "o-", ms=2.5, lw=1,
                    label="%s: rate error %.3g %%" % (label, 100 * err))
        if exact is None:
            exact = (p["t"], p["reference"])
    ax.semilogy(exact[0], exact[1], "k-", lw=2, label="exact exp(-16 pi^2 nu t / L^2)")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("E / E0")
    ax.set_title("Taylor-Green vortex, Re = 100")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(argv[1], dpi=90)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
