# Protocol, coordinator and nodes (brief C): common/protocol/link.c, common/protocol/transport.c, common/protocol/netns.c,
# coordinator/, dem_node/dem_node.c, sph_node/. The run tests need `unshare` of user + network
# namespaces and nft (label netns); each multicast run happens in a private namespace.
add_executable(test_coupling_clock ${LAHAR_TEST_DIR}/test_coupling_clock.c)
target_link_libraries(test_coupling_clock PRIVATE lahar_coord)
add_test(NAME coupling_clock COMMAND test_coupling_clock)
set_tests_properties(coupling_clock PROPERTIES LABELS "fast;coupling")

add_executable(test_coupling_link ${LAHAR_TEST_DIR}/test_coupling_link.c)
target_link_libraries(test_coupling_link PRIVATE lahar_common)
add_test(NAME coupling_link COMMAND test_coupling_link)
set_tests_properties(coupling_link PROPERTIES LABELS "fast;coupling" TIMEOUT 60)

add_executable(test_coupling_msg ${LAHAR_TEST_DIR}/test_coupling_msg.c)
target_link_libraries(test_coupling_msg PRIVATE lahar_common)
add_test(NAME coupling_msg COMMAND test_coupling_msg)
set_tests_properties(coupling_msg PROPERTIES LABELS "fast;coupling")

add_executable(test_coupling_scene ${LAHAR_TEST_DIR}/test_coupling_scene.c)
target_link_libraries(test_coupling_scene PRIVATE lahar_common)
add_test(NAME coupling_scene COMMAND test_coupling_scene ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR})
set_tests_properties(coupling_scene PROPERTIES LABELS "fast;coupling")

add_executable(test_sph_particles ${LAHAR_TEST_DIR}/test_sph_particles.c)
target_link_libraries(test_sph_particles PRIVATE lahar_sph)
add_test(NAME sph_particles COMMAND test_sph_particles)
set_tests_properties(sph_particles PROPERTIES LABELS "fast;coupling")

# coupling_runs.sh TEST BIN_DIR TOOLS_DIR WORK_DIR
function(lahar_coupling_run_test name labels)
  add_test(NAME coupling_${name}
           COMMAND bash ${LAHAR_TEST_DIR}/coupling_runs.sh ${name} $<TARGET_FILE_DIR:lahar>
                   ${CMAKE_SOURCE_DIR}/tools ${CMAKE_CURRENT_BINARY_DIR}/coupling_${name})
  set_tests_properties(coupling_${name} PROPERTIES LABELS "${labels}" TIMEOUT 180
                       DEPENDS "" REQUIRED_FILES "$<TARGET_FILE:lahar-dem>;$<TARGET_FILE:lahar-sph>")
endfunction()
lahar_coupling_run_test(inprocess_both "fast;coupling")
lahar_coupling_run_test(processes "fast;netns;coupling")
lahar_coupling_run_test(packet_loss "fast;netns;coupling")
lahar_coupling_run_test(node_killed "slow;netns;coupling")
lahar_coupling_run_test(node_stopped "slow;netns;coupling")
lahar_coupling_run_test(coordinator_killed "slow;netns;coupling")
lahar_coupling_run_test(concurrent "slow;netns;coupling")
lahar_coupling_run_test(cross_host "slow;netns;coupling")
# a hostile peer for the authenticated run (re-publishes what it hears altered, unsigned, verbatim)
add_executable(lahar_attack ${LAHAR_TEST_DIR}/lahar_attack.c)
target_link_libraries(lahar_attack PRIVATE PkgConfig::LCM)
lahar_coupling_run_test(cross_host_auth "slow;netns;coupling")
set_property(TEST coupling_cross_host_auth APPEND PROPERTY ENVIRONMENT "LAHAR_ATTACK=$<TARGET_FILE:lahar_attack>")
lahar_coupling_run_test(no_namespace "fast;netns;coupling")
lahar_coupling_run_test(engine_error "fast;coupling")
# a full disk on OUT (a small tmpfs in a private user + mount namespace): mid-run and at the start
lahar_coupling_run_test(disk_full "slow;netns;coupling")
lahar_coupling_run_test(disk_full_start "fast;netns;coupling")
lahar_coupling_run_test(cli "fast;netns;coupling")
