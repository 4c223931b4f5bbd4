# Hydrostatic tank: the library-level 2D tank with the ghost-layer wall
# pressure (LAHAR_SPH_WALL_PRESSURE_GHOST, sph_node/coupling/sph_coupling.h): side walls within 1 % of
# rho g H^2 / 2, floor + side walls carry the weight within 0.5 %, particle-row pressures from the
# first row (dx/2 above the floor, where the penalty wall alone reads +13 %) within 1 % RMS and
# 1.5 % max of rho g H. The case-level runs are validation_hydrostatic_2d/_3d (validation.cmake).
lahar_test(sph_hydrostatic_ghost COMMAND test_sph_hydrostatic 20 2 ghost LABELS fast sph hydro TIMEOUT 300)
# The Riemann scheme (sph.scheme: riemann) in the same tank and bounds with ghost walls, with
# riemann_limiter: 0 (the full acoustic dissipation) after 2 s (|v|max 1.7e-4 m/s, side walls
# +0.19 %, pressure RMS 0.47 %), and with the default limiter (3, Zhang et al. 2017) after 6 s:
# the limiter adds almost no dissipation at the small speeds of still water, so the start-up
# waves take longer to decay (|v|max 0.048 / 0.014 / 0.0074 m/s at 2 / 4 / 6 s, bound 0.014);
# the pressure rows (RMS 0.53 %), the wall forces (+0.22 %, +0.26 %) and the level surface hold.
lahar_test(sph_hydrostatic_riemann COMMAND test_sph_hydrostatic 20 2 ghost riemann 0 LABELS fast sph hydro TIMEOUT 300)
lahar_test(sph_hydrostatic_riemann_limiter COMMAND test_sph_hydrostatic 20 6 ghost riemann LABELS sph hydro TIMEOUT 300)
