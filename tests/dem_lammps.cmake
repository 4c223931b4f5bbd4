# The LAMMPS DEM engine (dem_node/engines/lammps): analytic checks of the engine, and a coupled run
# with `lahar run` against the spheropoly engine. Without liblammps the tests exist and report
# SKIP (exit 77), so a build without the engine says what it did not test.
lahar_test(test_dem_lammps SOURCES test_dem_lammps.c dem_test_util.c LIBS lahar_dem LABELS fast dem lammps TIMEOUT 300
  PROPERTIES SKIP_RETURN_CODE 77)
# `lahar-dem --engine lammps` on a case that names spheropoly (lahar run --no-spawn and the node
# started by hand in a private network namespace) against the same case run as usual; an unknown
# --engine refused.
lahar_test(dem_lammps_engine_option
  COMMAND bash ${LAHAR_TEST_DIR}/dem_lammps_engine_option.sh $<TARGET_FILE_DIR:lahar>
          ${CMAKE_CURRENT_BINARY_DIR}/dem_lammps_engine_option ${LAHAR_TEST_PYTHON}
  LABELS fast netns lammps coupling TIMEOUT 300)
if(NOT LAHAR_HAVE_LAMMPS)
  set_tests_properties(dem_lammps_engine_option PROPERTIES DISABLED TRUE)
endif()

if(LAHAR_SANITIZE)
  # OpenMPI's start-up state (MPI_Init inside liblammps) is suppressed in tests/lsan.supp by library;
  # that needs full stacks and the MCA components still loaded at exit to name them. The same for
  # the conformance suite's run of `lahar-dem --engine lammps` (tests/dem_conformance.cmake), whose
  # engine process inherits the environment.
  set_property(TEST test_dem_lammps dem_lammps_engine_option APPEND PROPERTY ENVIRONMENT
    "OMPI_MCA_mca_base_component_disable_dlclose=1;PMIX_MCA_mca_base_component_disable_dlclose=1;ASAN_OPTIONS=detect_leaks=1:fast_unwind_on_malloc=0;LSAN_OPTIONS=suppressions=${LAHAR_TEST_DIR}/lsan.supp:print_suppressions=0:fast_unwind_on_malloc=0")
  if(TEST dem_conformance_lammps)
    get_test_property(test_dem_lammps ENVIRONMENT lahar_lammps_env)
    # the leak check at exit with full unwinding adds seconds to the node's exit after it gave up on
    # the silent coordinator (measured 8.2 s against 5 s): the silence check allows 5 s more here
    set_property(TEST dem_conformance_lammps APPEND PROPERTY ENVIRONMENT "${lahar_lammps_env};LAHAR_CONFORMANCE_EXIT_SLACK=5")
  endif()
endif()


# A coupled run through `lahar run` (processes, private network namespace): a disc sinking in water
# onto the floor, lammps vs spheropoly (dem_lammps_coupled.sh says why the tolerance). ~20 s.
lahar_test(dem_lammps_coupled
  COMMAND sh ${LAHAR_TEST_DIR}/dem_lammps_coupled.sh $<TARGET_FILE:lahar> ${CMAKE_CURRENT_BINARY_DIR}/dem_lammps_coupled
          ${LAHAR_TEST_PYTHON}
  LABELS slow netns lammps coupling TIMEOUT 600)
if(NOT LAHAR_HAVE_LAMMPS)
  set_tests_properties(dem_lammps_coupled PROPERTIES DISABLED TRUE)
endif()

# Benchmark (not a test): per-substep cost of the lammps engine against spheropoly on a pile of
# spheres in a box of planes (built with everything, so that it cannot rot); run
# <dir>/bin/bench_dem_lammps (docs/bench/dem_lammps.md).
add_executable(bench_dem_lammps ${LAHAR_TEST_DIR}/bench/bench_dem_lammps.c ${LAHAR_TEST_DIR}/dem_test_util.c)
target_include_directories(bench_dem_lammps PRIVATE ${LAHAR_TEST_DIR})
target_link_libraries(bench_dem_lammps PRIVATE lahar_dem)

# The same coupled scene with both engines (cases/boulders_barrier_2d.yaml to 0.7 s, three runs
# in-process): the engines agree within 3x the spread of spheropoly between two SPH steps
# (dem_engines_compare.sh says why; numbers in docs/bench/dem_engines.md). ~2 min on 2 idle cores.
# Without the lammps engine it prints SKIP (exit 77).
lahar_test(dem_engines_compare
  COMMAND sh ${LAHAR_TEST_DIR}/dem_engines_compare.sh $<TARGET_FILE_DIR:lahar> ${CMAKE_SOURCE_DIR}/tools
          ${CMAKE_SOURCE_DIR}/cases/boulders_barrier_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/dem_engines_compare
          ${LAHAR_TEST_PYTHON}
  LABELS slow lammps coupling TIMEOUT 1200
  PROPERTIES SKIP_RETURN_CODE 77 REQUIRED_FILES "$<TARGET_FILE:lahar-dem>;$<TARGET_FILE:lahar-sph>")
