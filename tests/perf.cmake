# SPH speed.
# The SPH benchmark (tests/bench/bench_sph.c): 80k-particle 2D and 100k-particle 3D dam breaks on
# 1 and 2 threads, run by the `bench` target after the DEM table (never a pass/fail; it prints a table).
# Built with everything (not EXCLUDE_FROM_ALL), so that -Werror and every refactoring see it.
add_executable(bench_sph ${LAHAR_TEST_DIR}/bench/bench_sph.c)
target_link_libraries(bench_sph PRIVATE lahar_sph)
add_custom_target(bench_sph_table COMMAND bench_sph DEPENDS bench_sph WORKING_DIRECTORY ${CMAKE_SOURCE_DIR} USES_TERMINAL
  COMMENT "bench_sph: SPH step cost, 80k 2D and 100k 3D dam breaks on 1 and 2 threads")
add_dependencies(bench bench_sph_table)

# No allocation inside the SPH step in the steady state: malloc & co. wrapped by the linker.
add_executable(test_sph_noalloc ${LAHAR_TEST_DIR}/test_sph_noalloc.c ${LAHAR_TEST_DIR}/alloc_count.c ${LAHAR_TEST_DIR}/test_bodies.c)
target_link_libraries(test_sph_noalloc PRIVATE lahar_sph -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free)
lahar_test(sph_noalloc COMMAND test_sph_noalloc LABELS fast perf sph TIMEOUT 120
  ENVIRONMENT "OMP_NUM_THREADS=2")
