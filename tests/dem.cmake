# DEM engine and geometry tests. `fast` ones also run under the sanitizers in CI.
function(lahar_dem_test name label)
  add_executable(${name} ${LAHAR_TEST_DIR}/${name}.c ${LAHAR_TEST_DIR}/dem_test_util.c)
  target_include_directories(${name} PRIVATE ${LAHAR_TEST_DIR})
  target_link_libraries(${name} PRIVATE lahar_dem)
    lahar_test(${name} COMMAND ${name} LABELS ${label} dem TIMEOUT 300)
endfunction()

lahar_dem_test(test_geometry fast)
lahar_dem_test(test_dem_bounce fast)
lahar_dem_test(test_dem_incline fast)
lahar_dem_test(test_dem_slide fast)
lahar_dem_test(test_dem_freebody fast)
lahar_dem_test(test_dem_stack fast)
lahar_dem_test(test_dem_restart fast)
lahar_dem_test(test_dem_prescribed fast)
lahar_dem_test(test_dem_spheres fast)

# The settling pile of the benchmark (tests/bench/dem_pile.h), also used by test_dem_noalloc.
add_library(lahar_dem_pile STATIC ${LAHAR_TEST_DIR}/bench/dem_pile.c ${LAHAR_TEST_DIR}/dem_test_util.c)
target_include_directories(lahar_dem_pile PUBLIC ${LAHAR_TEST_DIR} ${LAHAR_TEST_DIR}/bench)
target_link_libraries(lahar_dem_pile PUBLIC lahar_dem)

# No allocation inside advance() in the steady state: malloc & co. wrapped by the linker.
add_executable(test_dem_noalloc ${LAHAR_TEST_DIR}/test_dem_noalloc.c ${LAHAR_TEST_DIR}/alloc_count.c)
target_link_libraries(test_dem_noalloc PRIVATE lahar_dem_pile
  -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free)
lahar_test(test_dem_noalloc COMMAND test_dem_noalloc LABELS fast dem TIMEOUT 300)

# Benchmarks (tests/bench/, not ctest tests: they print a table and never fail on time).
# `cmake --build <dir> --target bench` builds and runs bench_dem with its default sizes.
add_executable(bench_dem ${LAHAR_TEST_DIR}/bench/bench_dem.c ${LAHAR_TEST_DIR}/bench/bench_lammps.c)
target_link_libraries(bench_dem PRIVATE lahar_dem_pile)
# bench_dem --lammps-data also runs LAMMPS through its C library when liblammps-dev is installed
# (-DLAHAR_BENCH_LAMMPS=OFF: without it, e.g. for valgrind, which stops on liblammps's start-up code)
option(LAHAR_BENCH_LAMMPS "bench_dem runs LAMMPS through liblammps when it is installed" ON)
if(LAHAR_BENCH_LAMMPS)
  pkg_check_modules(LAMMPS IMPORTED_TARGET liblammps)
endif()
if(LAHAR_BENCH_LAMMPS AND LAMMPS_FOUND)
  target_link_libraries(bench_dem PRIVATE PkgConfig::LAMMPS)
  target_compile_definitions(bench_dem PRIVATE LAHAR_HAVE_LAMMPS)
endif()
add_custom_target(bench COMMAND bench_dem DEPENDS bench_dem WORKING_DIRECTORY ${CMAKE_SOURCE_DIR} USES_TERMINAL
  COMMENT "bench_dem: DEM step cost for 500/2000/8000 bodies on 1 and 2 threads")

# The sphere fast path against LAMMPS on a small settled pile (contact count, KE decay); skipped
# without lmp / liblammps (tests/dem_lammps_check.sh).
lahar_test(dem_lammps_pile COMMAND sh ${LAHAR_TEST_DIR}/dem_lammps_check.sh $<TARGET_FILE:bench_dem> ${CMAKE_CURRENT_BINARY_DIR}/dem_lammps_pile
  LABELS slow dem TIMEOUT 300 PROPERTIES SKIP_RETURN_CODE 77)
