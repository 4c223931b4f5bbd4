#!/bin/sh
# Stability stress suite: sweeps that find the solver's limits and report, per setting,
# how the run ended and what caught a failure. See tests/stress/stress.py and README.md
# ("Stability limits").
#   tests/stress/run_stress.sh                 short sweeps (coarse, a few minutes on 2 cores)
#   tests/stress/run_stress.sh --full          finer and longer sweeps, plus the 10^6-step tank
#   tests/stress/run_stress.sh --only c0,cfl   some sweeps (cfl c0 dem_stiffness boulder soil_wall
#                                              density_ratio hydrostatic_1e6)
#   options: --out DIR (default stress_out), --lahar PATH (default build/bin/lahar), --threads N
# Runs are niced (nice -n 5) and one at a time: the machine is shared.
here=$(cd "$(dirname "$0")" && pwd)
exec nice -n 5 /usr/bin/python3 "$here/stress.py" sweep "$@"
