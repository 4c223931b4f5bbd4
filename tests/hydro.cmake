# Hydrostatic tank (brief HYDRO, issue 3): the library-level 2D tank with the ghost-layer wall
# pressure (LAHAR_SPH_WALL_PRESSURE_GHOST, sph_node/coupling/sph_coupling.h): side walls within 1 % of
# rho g H^2 / 2, floor + side walls carry the weight within 0.5 %, particle-row pressures from the
# first row (dx/2 above the floor, where the penalty wall alone reads +13 %) within 1 % RMS and
# 1.5 % max of rho g H. The case-level runs are validation_hydrostatic_2d/_3d (validation.cmake).
add_test(NAME sph_hydrostatic_ghost COMMAND test_sph_hydrostatic 20 2 ghost)
set_tests_properties(sph_hydrostatic_ghost PROPERTIES LABELS "fast;sph;hydro" TIMEOUT 300)
