# One recipe for every folder's library: public headers under include/, sources
# beside them, warnings on, and a namespaced alias (shatter::<name>).
function(shatter_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(shatter_${name} ${ARG_SOURCES})
  add_library(shatter::${name} ALIAS shatter_${name})
  target_include_directories(shatter_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>)
  target_link_libraries(shatter_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  shatter_warnings(shatter_${name})
endfunction()

function(shatter_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion)
  if(SHATTER_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
