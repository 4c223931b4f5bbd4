# SPH node driving the WCSPH core and the SPH-DEM coupling over the protocol:
# sph_node/node/node_loop.c, dem_node/dem_node.c (LOADS, BODY_STATE), contacts.h5 (common/io/output_contacts.c).
# coupling_sph_runs.sh TEST BIN_DIR TOOLS_DIR WORK_DIR; `modes` runs nodes as processes in lahar's
# own private network namespace (label netns).
function(lahar_coupling_sph_test name labels)
    lahar_test(coupling_sph_${name} COMMAND bash ${LAHAR_TEST_DIR}/coupling_sph_runs.sh ${name} $<TARGET_FILE_DIR:lahar> ${CMAKE_SOURCE_DIR}/tools ${CMAKE_CURRENT_BINARY_DIR}/coupling_sph_${name}
    LABELS ${labels} TIMEOUT 180 PROPERTIES REQUIRED_FILES "$<TARGET_FILE:lahar-dem>;$<TARGET_FILE:lahar-sph>")
endfunction()
lahar_coupling_sph_test(modes "fast;netns;coupling")
lahar_coupling_sph_test(far_body "fast;coupling")
lahar_coupling_sph_test(hydrostatic "fast;coupling")
lahar_coupling_sph_test(crossing "fast;coupling")
lahar_coupling_sph_test(dem_killed "slow;netns;coupling")
