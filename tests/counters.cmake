# Work counters and "nothing computed that a scene does not need":
# summary.json "work" (coordinator/README.md) against independent counts, a scene of water and
# fixed bodies without a DEM node, output fields not asked for not computed.
# counters_runs.sh TEST BIN_DIR TOOLS_DIR WORK_DIR (runs --in-process; `processes` runs the nodes as
# processes in lahar's own private network namespace: label netns).
function(lahar_counters_test name labels)
    lahar_test(counters_${name} COMMAND bash ${LAHAR_TEST_DIR}/counters_runs.sh ${name} $<TARGET_FILE_DIR:lahar> ${CMAKE_SOURCE_DIR}/tools ${CMAKE_CURRENT_BINARY_DIR}/counters_${name}
    LABELS ${labels} TIMEOUT 180 PROPERTIES REQUIRED_FILES "$<TARGET_FILE:lahar-dem>;$<TARGET_FILE:lahar-sph>")
endfunction()
lahar_counters_test(water_only "fast;counters")
lahar_counters_test(soil_water "fast;counters")
lahar_counters_test(fixed_bodies "fast;counters")
lahar_counters_test(processes "fast;netns;counters")
lahar_counters_test(output_fields "fast;counters")
lahar_counters_test(dem_contacts "fast;counters")
