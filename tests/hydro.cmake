# Hydrostatic tank: the library-level 2D tank with the ghost-layer wall
# pressure (LAHAR_SPH_WALL_PRESSURE_GHOST, sph_node/coupling/sph_coupling.h): side walls within 1 % of
# rho g H^2 / 2, floor + side walls carry the weight within 0.5 %, particle-row pressures from the
# first row (dx/2 above the floor, where the penalty wall alone reads +13 %) within 1 % RMS and
# 1.5 % max of rho g H. The case-level runs are validation_hydrostatic_2d/_3d (validation.cmake).
lahar_test(sph_hydrostatic_ghost COMMAND test_sph_hydrostatic 20 2 ghost LABELS fast sph hydro TIMEOUT 300)
# The Riemann scheme (sph.scheme: riemann) in the same tank and bounds with ghost walls and
# riemann_limiter: 0 (the full acoustic dissipation): the low-dissipation limiter (default 3) adds
# almost no dissipation at the small speeds of still water, and the tank is still sloshing after
# 2 s (|v|max 0.048 m/s against the bound 0.044); with the full dissipation it settles
# (|v|max 1.7e-4 m/s, side walls +0.19 %, pressure RMS 0.50 %).
lahar_test(sph_hydrostatic_riemann COMMAND test_sph_hydrostatic 20 2 ghost riemann 0 LABELS fast sph hydro TIMEOUT 300)
