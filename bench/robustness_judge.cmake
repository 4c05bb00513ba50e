# The robustness judge's side rules on a hand-made corpus of the cube [-1, 1]^3
# (tests/data/corpus/cube.off), for shatter: a plane through the middle (both sides
# written), a plane that misses the cube (one side, nothing lost or spurious), and a
# plane that leaves the vertex (1, 1, 1) above it by far less than the rounding of
# its coordinates (shatter-fuzz seed 20261129, case 63: the exact sliver above has no
# valid double form and vanishes, so writing nothing there is right, not a lost side).
# Every case must be ok.
# Called with -DBENCH=<shatter-bench-robustness> -DMESH=<cube.off> -DWORK=<scratch folder>.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}/meshes")
file(COPY "${MESH}" DESTINATION "${WORK}/meshes")
get_filename_component(mesh_name "${MESH}" NAME)
set(cases "")
set(id 0)
foreach(plane
    "\"0x1p+0\", \"0x0p+0\", \"0x0p+0\", \"0x0p+0\""
    "\"0x1p+0\", \"0x0p+0\", \"0x0p+0\", \"-0x1.4p+2\""
    "\"0x1.9e294eae56b9ap-6\", \"0x1.a2c6bb5b736ecp-2\", \"0x1.d30c15c9d7ed2p-1\", \"-0x1.58b05ef6822d2p+0\"")
  if(id GREATER 0)
    string(APPEND cases ",")
  endif()
  string(APPEND cases "{\"id\": ${id}, \"class\": \"judge\", \"mesh\": \"meshes/${mesh_name}\", \"operation\": \"slice\", \"planes_hex\": [[${plane}]]}")
  math(EXPR id "${id} + 1")
endforeach()
file(WRITE "${WORK}/manifest.json" "{\"cases\": [${cases}]}")
execute_process(COMMAND "${BENCH}" "${WORK}" --tools shatter --csv "${WORK}/judge.csv"
                RESULT_VARIABLE status OUTPUT_VARIABLE table)
message("${table}")
if(NOT status EQUAL 0)
  message(FATAL_ERROR "shatter-bench-robustness failed: ${status}")
endif()
if(NOT table MATCHES "\\| all \\| 3 / 0 / 0 / 0 / 0 \\|")
  file(READ "${WORK}/judge.csv" rows)
  message(FATAL_ERROR "the judge did not pass shatter's three cuts of the cube:\n${rows}")
endif()
file(REMOVE_RECURSE "${WORK}")
