# Fuzzing (tests/fuzz/README.md): the case loader, the link's receive path and the typed message
# decoders. In every build, each harness is linked with a replay driver and replays its seed
# corpus and the reproducers of what fuzzing found (label fast, so the ASan + UBSan build of CI
# re-checks them). With -DLAHAR_FUZZ=ON (clang) the same harnesses are also libFuzzer programs.
set(LAHAR_FUZZ_DIR ${LAHAR_TEST_DIR}/fuzz)
set(LAHAR_FUZZ_TARGETS case link msg)
set(LAHAR_FUZZ_case_SEEDS ${CMAKE_SOURCE_DIR}/cases ${LAHAR_TEST_DIR}/bad_cases ${LAHAR_FUZZ_DIR}/corpus/case)
set(LAHAR_FUZZ_link_SEEDS ${LAHAR_FUZZ_DIR}/corpus/link)
set(LAHAR_FUZZ_msg_SEEDS ${LAHAR_FUZZ_DIR}/corpus/msg)

function(lahar_fuzz_sources out t)
  set(${out} ${LAHAR_FUZZ_DIR}/fuzz_${t}.c ${LAHAR_FUZZ_DIR}/fuzz_decode.c PARENT_SCOPE)
endfunction()

foreach(t ${LAHAR_FUZZ_TARGETS})
  lahar_fuzz_sources(src ${t})
  add_executable(fuzz_${t}_replay ${src} ${LAHAR_FUZZ_DIR}/replay_main.c ${LAHAR_FUZZ_DIR}/fuzz_file.c)
  target_include_directories(fuzz_${t}_replay PRIVATE ${LAHAR_FUZZ_DIR})
  target_compile_definitions(fuzz_${t}_replay PRIVATE LAHAR_FUZZ_CASE_PATH="${CMAKE_SOURCE_DIR}/cases/fuzz.yaml")
  target_link_libraries(fuzz_${t}_replay PRIVATE lahar_common)
    lahar_test(fuzz_${t}_replay COMMAND fuzz_${t}_replay ${LAHAR_FUZZ_${t}_SEEDS} ${LAHAR_FUZZ_DIR}/regressions/${t}
    LABELS fast fuzz)
endforeach()

# the message seeds: tests/fuzz/make_seeds.c (rerun and commit when a message type changes)
add_executable(fuzz_make_seeds ${LAHAR_FUZZ_DIR}/make_seeds.c ${LAHAR_FUZZ_DIR}/fuzz_decode.c ${LAHAR_FUZZ_DIR}/fuzz_file.c)
target_include_directories(fuzz_make_seeds PRIVATE ${LAHAR_FUZZ_DIR})
target_link_libraries(fuzz_make_seeds PRIVATE lahar_common)
# ... and the committed seeds and scene reproducers are what it writes now: a message type changed
# without rerunning it leaves seeds and reproducers that fail at the type hash and no longer reach
# the decoders' checks; doubles may differ by round-off of the C library between CPUs (make_seeds.c
# says why) (not `fast`: make_seeds is a generator, not checked for leaks)
set(w ${CMAKE_CURRENT_BINARY_DIR}/fuzz_seeds_current)
lahar_test(fuzz_seeds_current COMMAND sh -c "rm -rf \"$2\" && mkdir -p \"$2/corpus/msg\" \"$2/corpus/link\" \"$2/regressions/msg\" && \"$0\" \"$1/cases\" \"$2/corpus\" && \"$0\" --compare \"$2/corpus/msg\" \"$1/tests/fuzz/corpus/msg\" && \"$0\" --compare \"$2/corpus/link\" \"$1/tests/fuzz/corpus/link\" && \"$0\" --compare-written \"$2/regressions/msg\" \"$1/tests/fuzz/regressions/msg\""
  $<TARGET_FILE:fuzz_make_seeds> ${CMAKE_SOURCE_DIR} ${w} LABELS fuzz)

if(LAHAR_FUZZ)
  if(NOT CMAKE_C_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "LAHAR_FUZZ=ON needs clang for libFuzzer: configure with -DCMAKE_C_COMPILER=clang")
  endif()
  foreach(t ${LAHAR_FUZZ_TARGETS})
    lahar_fuzz_sources(src ${t})
    add_executable(fuzz_${t} ${src})
    target_include_directories(fuzz_${t} PRIVATE ${LAHAR_FUZZ_DIR})
    target_compile_definitions(fuzz_${t} PRIVATE LAHAR_FUZZ_CASE_PATH="${CMAKE_SOURCE_DIR}/cases/fuzz.yaml")
    target_link_libraries(fuzz_${t} PRIVATE lahar_common)
    target_link_options(fuzz_${t} PRIVATE -fsanitize=fuzzer)
  endforeach()
endif()
