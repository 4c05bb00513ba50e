# CTest's "install and consume" test, run as cmake -P with:
#   BUILD_DIR      shatter's build tree (installed from)
#   SOURCE_DIR     tests/consumer
#   WORK_DIR       a scratch folder (emptied first)
#   VERSION        the version the package must report
#   CXX_FLAGS      compile and link flags the consumer needs to match the build
#                  (a sanitized build's -fsanitize=...), may be empty
#   EACH_HEADER    ON (the default) to compile each installed header on its own too
# Installs the build into WORK_DIR/prefix, configures the consumer against that
# prefix alone, builds it, checks that nothing it compiled included CGAL, GMP or
# MPFR, runs it, and runs the installed `shatter --version`.
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

# No installed header reaches CGAL, GMP or MPFR: they are private dependencies of
# the libraries (linked, never included). Their headers sit in /usr/include with
# everything else, so a header that included one would still compile here; the
# check reads what every object of the consumer (each header alone, cut_a_cube)
# really included, from the dependency lists Ninja recorded while compiling.
file(STRINGS "${WORK_DIR}/build/CMakeCache.txt" make_program REGEX "^CMAKE_MAKE_PROGRAM:")
string(REGEX REPLACE "^[^=]*=" "" make_program "${make_program}")
run("${make_program}" -C "${WORK_DIR}/build" -t deps)
string(REPLACE "\n" ";" dependency_lines "${last_output}")
set(object "")
set(objects 0)
set(header_objects 0)
set(offenders "")
foreach(line IN LISTS dependency_lines)
  if(line MATCHES "^([^ ].*): #deps [1-9]")
    set(object "${CMAKE_MATCH_1}")
    math(EXPR objects "${objects} + 1")
    if(object MATCHES "each_header")
      math(EXPR header_objects "${header_objects} + 1")
    endif()
  elseif(line MATCHES "/(CGAL/.*|gmpxx\\.h|gmp\\.h|mpfr\\.h)$")
    list(APPEND offenders "${object} includes ${CMAKE_MATCH_1}")
  endif()
endforeach()
if(EACH_HEADER AND header_objects LESS 40)
  message(FATAL_ERROR "Ninja recorded the includes of ${header_objects} header objects, expected 40 or more:\n${last_output}")
endif()
if(objects EQUAL 0)
  message(FATAL_ERROR "Ninja recorded no includes for the consumer's objects:\n${last_output}")
endif()
if(offenders)
  list(REMOVE_DUPLICATES offenders)
  list(JOIN offenders "\n  " offenders)
  message(FATAL_ERROR "installed headers reach CGAL, GMP or MPFR, which the package keeps private:\n  ${offenders}")
endif()
message(STATUS "none of the ${objects} consumer objects (${header_objects} installed headers alone) includes CGAL, GMP or MPFR")
run("${WORK_DIR}/build/cut_a_cube")
message(STATUS "${last_output}")
run("${WORK_DIR}/prefix/bin/shatter" --version)
if(NOT last_output STREQUAL "shatter ${VERSION}\n")
  message(FATAL_ERROR "the installed shatter --version printed '${last_output}', not 'shatter ${VERSION}'")
endif()
