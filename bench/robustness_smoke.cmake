# The robustness comparison end to end on a small corpus, so CI notices when
# either half breaks: shatter-fuzz exports 32 cases, shatter-bench-robustness runs
# them through every tool. Fails when a command fails, or when shatter (the first
# column) wrote an invalid piece, crashed or timed out; the peers' outcomes are
# what is measured, never a failure.
# Called with -DFUZZ=<shatter-fuzz> -DBENCH=<shatter-bench-robustness> -DWORK=<scratch folder>.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
execute_process(COMMAND "${FUZZ}" --export-corpus "${WORK}/corpus" --cases 32 --seed 7 RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "shatter-fuzz --export-corpus failed: ${status}")
endif()
# A case's time limit is a hang detector, not a speed test: shatter's slowest case
# here (28, a near-parallel chain on the hollow egg, which it refuses after trying
# every wedge split round_solid has) takes 11.5 s alone and over 30 s on a machine
# three other builds share (2026-12-05), so the limit is 90 s.
execute_process(COMMAND "${BENCH}" "${WORK}/corpus" --timeout 90 --csv "${WORK}/robustness.csv"
                RESULT_VARIABLE status OUTPUT_VARIABLE table)
message("${table}")
if(NOT status EQUAL 0)
  message(FATAL_ERROR "shatter-bench-robustness failed: ${status}")
endif()
if(NOT table MATCHES "\\| all \\| [0-9]+ / 0 / [0-9]+ / 0 / 0 \\|")
  message(FATAL_ERROR "shatter wrote an invalid piece, crashed or timed out on the smoke corpus")
endif()
file(REMOVE_RECURSE "${WORK}")
