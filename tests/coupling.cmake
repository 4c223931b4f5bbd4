# Protocol, coordinator and nodes: common/protocol/link.c, common/protocol/transport.c, common/protocol/netns.c,
# coordinator/, dem_node/dem_node.c, sph_node/. The run tests need `unshare` of user + network
# namespaces and nft (label netns); each multicast run happens in a private namespace.
lahar_test(coupling_clock PROGRAM test_coupling_clock SOURCES test_coupling_clock.c
  LIBS lahar_coord LABELS fast coupling)

lahar_test(machine_load PROGRAM test_machine_load SOURCES test_machine_load.c
  LIBS lahar_coord LABELS fast coupling)

lahar_test(coupling_link PROGRAM test_coupling_link SOURCES test_coupling_link.c
  LABELS fast coupling TIMEOUT 60)

lahar_test(coupling_msg PROGRAM test_coupling_msg SOURCES test_coupling_msg.c LABELS fast coupling)

lahar_test(coupling_scene PROGRAM test_coupling_scene SOURCES test_coupling_scene.c
  ARGS ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR} LABELS fast coupling)

lahar_test(sph_particles PROGRAM test_sph_particles SOURCES test_sph_particles.c
  LIBS lahar_sph LABELS fast coupling)

# coupling_runs.sh TEST BIN_DIR TOOLS_DIR WORK_DIR
function(lahar_coupling_run_test name labels)
    lahar_test(coupling_${name} COMMAND bash ${LAHAR_TEST_DIR}/coupling_runs.sh ${name} $<TARGET_FILE_DIR:lahar> ${CMAKE_SOURCE_DIR}/tools ${CMAKE_CURRENT_BINARY_DIR}/coupling_${name}
    LABELS ${labels} TIMEOUT 180
    PROPERTIES REQUIRED_FILES "$<TARGET_FILE:lahar-dem>;$<TARGET_FILE:lahar-sph>")
endfunction()
lahar_coupling_run_test(inprocess_both "fast;coupling")
lahar_coupling_run_test(processes "fast;netns;coupling")
lahar_coupling_run_test(busy_machine "fast;netns;coupling")
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
