# The Manifold worker's faults are counted per case, never fatal: with a worker that
# refuses, crashes (SIGSEGV) and hangs in turn (robustness_fault_worker.mjs),
# shatter-bench-robustness must finish and count 3 refused, 1 crashed and 1 timeout
# over 5 cases, restarting the worker after the crash and after the hang.
# Called with -DNODE=<node> -DFUZZ=<shatter-fuzz> -DBENCH=<shatter-bench-robustness>
# -DWORKER=<robustness_fault_worker.mjs> -DWORK=<scratch folder>.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
execute_process(COMMAND "${FUZZ}" --export-corpus "${WORK}/corpus" --cases 16 --seed 7 RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "shatter-fuzz --export-corpus failed: ${status}")
endif()
set(ENV{FAULT_COUNT} "${WORK}/count")
execute_process(COMMAND "${BENCH}" "${WORK}/corpus" --tools manifold --node "${NODE}" --manifold-worker "${WORKER}"
                        --timeout 3 --max-cases 5
                RESULT_VARIABLE status OUTPUT_VARIABLE table)
message("${table}")
if(NOT status EQUAL 0)
  message(FATAL_ERROR "shatter-bench-robustness failed: ${status}")
endif()
if(NOT table MATCHES "\\| all \\| 0 / 0 / 3 / 1 / 1 \\|")
  message(FATAL_ERROR "the worker's refusal, crash and hang were not counted as 3 refused, 1 crashed, 1 timeout")
endif()
file(REMOVE_RECURSE "${WORK}")
