# Coordinated checkpoints and `lahar resume` (coordinator/README.md "Checkpoints and resume"): an
# interrupted or early-ended run, resumed, ends with output bitwise equal to the uninterrupted
# run's (water, DEM only, coupled with the DEM node and then the resumed run's SPH node killed by SIGKILL, soil, SIGTERM; SIGTERM and SIGHUP to lahar's whole process group, a log pipe that closed; a disk that fills up before a checkpoint; lahar itself killed), SIGUSR1 writes a
# checkpoint, and the errors a user can meet exit 2 with a message. Runs use lahar's own private
# network namespace (label netns) or --in-process.
# checkpoint_runs.sh TEST BIN_DIR TOOLS_DIR CASES_DIR WORK_DIR
function(lahar_checkpoint_test name labels)
    lahar_test(checkpoint_${name} COMMAND bash ${LAHAR_TEST_DIR}/checkpoint_runs.sh ${name} $<TARGET_FILE_DIR:lahar> ${CMAKE_SOURCE_DIR}/tools ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR}/checkpoint_${name}
    LABELS ${labels} TIMEOUT 180 PROPERTIES REQUIRED_FILES "$<TARGET_FILE:lahar-dem>;$<TARGET_FILE:lahar-sph>")
endfunction()
lahar_checkpoint_test(water "slow;netns;checkpoint")
lahar_checkpoint_test(dem "fast;netns;checkpoint")
lahar_checkpoint_test(coupled_killed "slow;netns;checkpoint")
lahar_checkpoint_test(soil "slow;checkpoint")
lahar_checkpoint_test(sigterm "slow;netns;checkpoint")
lahar_checkpoint_test(group_signals "slow;netns;checkpoint")
lahar_checkpoint_test(disk_full "slow;netns;checkpoint")
lahar_checkpoint_test(coordinator_killed "slow;netns;checkpoint")
lahar_checkpoint_test(sigusr1 "slow;netns;checkpoint")
lahar_checkpoint_test(errors "slow;netns;checkpoint")
lahar_checkpoint_test(inflow "fast;netns;checkpoint")
