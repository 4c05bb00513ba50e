# CTest's "install and consume" test, run as cmake -P with:
#   BUILD_DIR      shatter's build tree (installed from)
#   SOURCE_DIR     tests/consumer
#   WORK_DIR       a scratch folder (emptied first)
#   VERSION        the version the package must report
#   CXX_FLAGS      compile and link flags the consumer needs to match the build
#                  (a sanitized build's -fsanitize=...), may be empty
#   EACH_HEADER    ON (the default) to compile each installed header on its own too
# Installs the build into WORK_DIR/prefix, configures the consumer against that
# prefix alone, builds it and runs it, and runs the installed `shatter --version`.
if(NOT DEFINED EACH_HEADER)
  set(EACH_HEADER ON)
endif()
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR VERSION)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_consumer.cmake needs -D${var}=...")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "failed (${code}): ${ARGV}\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix")
run(${CMAKE_COMMAND} -S "${SOURCE_DIR}" -B "${WORK_DIR}/build" -G Ninja -DCMAKE_BUILD_TYPE=Release
    "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix" "-DEXPECTED_SHATTER_VERSION=${VERSION}"
    "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${CXX_FLAGS}" "-DEACH_HEADER=${EACH_HEADER}")
run(${CMAKE_COMMAND} --build "${WORK_DIR}/build")
run("${WORK_DIR}/build/cut_a_cube")
message(STATUS "${last_output}")
run("${WORK_DIR}/prefix/bin/shatter" --version)
if(NOT last_output STREQUAL "shatter ${VERSION}\n")
  message(FATAL_ERROR "the installed shatter --version printed '${last_output}', not 'shatter ${VERSION}'")
endif()
