# SPH solver core (brief E): kernels (common/kernels/kernel.c), particles, cell lists, WCSPH and the
# SPH-DEM coupling (sph_node/sph_*.c), tested at library level without processes.
add_executable(test_kernel ${LAHAR_TEST_DIR}/test_kernel.c)
target_link_libraries(test_kernel PRIVATE lahar_common)
add_test(NAME sph_kernel COMMAND test_kernel)
set_tests_properties(sph_kernel PROPERTIES LABELS "fast;sph")

add_executable(test_sph_poiseuille ${LAHAR_TEST_DIR}/test_sph_poiseuille.c)
target_link_libraries(test_sph_poiseuille PRIVATE lahar_sph)
add_test(NAME sph_poiseuille COMMAND test_sph_poiseuille)
set_tests_properties(sph_poiseuille PROPERTIES LABELS "fast;sph" TIMEOUT 300)

add_executable(test_sph_fluid ${LAHAR_TEST_DIR}/test_sph_fluid.c)
target_link_libraries(test_sph_fluid PRIVATE lahar_sph)
add_test(NAME sph_fluid COMMAND test_sph_fluid)
set_tests_properties(sph_fluid PROPERTIES LABELS "fast;sph" TIMEOUT 120)

add_executable(test_sph_coupling ${LAHAR_TEST_DIR}/test_sph_coupling.c)
target_link_libraries(test_sph_coupling PRIVATE lahar_sph)
add_test(NAME sph_coupling COMMAND test_sph_coupling)
set_tests_properties(sph_coupling PROPERTIES LABELS "fast;sph" TIMEOUT 120)

add_executable(test_sph_hydrostatic ${LAHAR_TEST_DIR}/test_sph_hydrostatic.c)
target_link_libraries(test_sph_hydrostatic PRIVATE lahar_sph)
add_test(NAME sph_hydrostatic COMMAND test_sph_hydrostatic)
set_tests_properties(sph_hydrostatic PROPERTIES LABELS "fast;sph" TIMEOUT 120)

add_executable(test_sph_hydrostatic3d ${LAHAR_TEST_DIR}/test_sph_hydrostatic3d.c)
target_link_libraries(test_sph_hydrostatic3d PRIVATE lahar_sph)
add_test(NAME sph_hydrostatic3d COMMAND test_sph_hydrostatic3d 10 3 ghost)
set_tests_properties(sph_hydrostatic3d PROPERTIES LABELS "slow;sph" TIMEOUT 600)

add_executable(test_sph_couette ${LAHAR_TEST_DIR}/test_sph_couette.c)
target_link_libraries(test_sph_couette PRIVATE lahar_sph)
add_test(NAME sph_couette COMMAND test_sph_couette)
set_tests_properties(sph_couette PROPERTIES LABELS "fast;sph" TIMEOUT 120)

# SPS turbulence (brief L): nu_t of a uniform shear, zero force of a constant stress, a shear wave
# against the analytic divergence, a dam break that stays stable.
add_executable(test_sph_sps ${LAHAR_TEST_DIR}/test_sph_sps.c)
target_link_libraries(test_sph_sps PRIVATE lahar_sph)
add_test(NAME sph_sps COMMAND test_sph_sps)
set_tests_properties(sph_sps PROPERTIES LABELS "fast;sph" TIMEOUT 120)

# Split step: step_begin + step_end integrate at second order in time (observed order at dt, dt/2, dt/4).
add_executable(test_sph_split ${LAHAR_TEST_DIR}/test_sph_split.c)
target_link_libraries(test_sph_split PRIVATE lahar_sph)
add_test(NAME sph_split COMMAND test_sph_split)
set_tests_properties(sph_split PROPERTIES LABELS "fast;sph" TIMEOUT 180 ENVIRONMENT "OMP_NUM_THREADS=2")

# Open boundaries (sph_node/inflow/sph_inflow.h): discharge through an inlet against the Gumbel
# hydrograph (Trujillo-Vela et al. 2020, eq. 36), a CSV t,Q table and a level table t,h, a 3D
# inlet, mass balance, outflow counts, unique ids, the capacity error, a supercritical channel at
# its steady depth.
add_executable(test_sph_inflow ${LAHAR_TEST_DIR}/test_sph_inflow.c)
target_link_libraries(test_sph_inflow PRIVATE lahar_sph)
add_test(NAME sph_inflow COMMAND test_sph_inflow)
set_tests_properties(sph_inflow PROPERTIES LABELS "fast;sph" TIMEOUT 300)
