# Stability stress suite, the short version: an unstable setting is caught (exit 1,
# status "unstable", what/where/when in summary.json and on stderr, the final snapshots readable,
# marked and at the failing step) and the safe settings finish. The sweeps that find the limits
# run on demand: tests/stress/run_stress.sh [--full] (README.md "Stability limits").
function(lahar_stress_test name)
    lahar_test(stress_${name} COMMAND /usr/bin/python3 ${LAHAR_TEST_DIR}/stress/stress.py ci ${name} --lahar $<TARGET_FILE:lahar> --out ${CMAKE_CURRENT_BINARY_DIR}/stress_${name}
    LABELS slow stress TIMEOUT 120
    PROPERTIES REQUIRED_FILES "$<TARGET_FILE:lahar-dem>;$<TARGET_FILE:lahar-sph>")
endfunction()
lahar_stress_test(density_band)
lahar_stress_test(dt_collapse)
lahar_stress_test(overlap)
lahar_stress_test(runaway)
lahar_stress_test(soil_wall)
lahar_stress_test(stable)

lahar_test(stress_instability_report PROGRAM test_instability SOURCES test_instability.c LABELS fast stress)
