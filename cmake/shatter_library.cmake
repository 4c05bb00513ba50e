# One recipe for every folder's library: public headers under include/, sources
# beside them, warnings on, a namespaced alias (shatter::<name>), and installed
# with its headers into the shatterTargets export set, under the same name
# (top-level CMakeLists.txt installs the set and shatterConfig.cmake).
# INTERNAL: a helper of the tests and benchmarks (shatter::generators), built the
# same way but neither installed nor exported, so the package promises no API it
# does not mean to keep.
#
# A folder's internal/ holds headers that are not installed (the exact-arithmetic
# API on CGAL and GMP types: shatter/kernel/exact.hpp, rationals.hpp, ...): the
# library's sources, the other libraries' sources and the tests include them, an
# installed consumer never sees them. So internal/ is on the include path of the
# build tree only, and BUILD_DEPS are what those headers need: usage requirements
# of this library and of every in-tree target that links it, absent from the
# export. A build dependency with a library to link (GMP, MPFR) is listed under
# PRIVATE_DEPS as well, which a static library's export keeps as link-only; a
# header-only one (CGAL) is not, so the installed package does not need it at all.
function(shatter_library name)
  cmake_parse_arguments(ARG "INTERNAL" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS;BUILD_DEPS" ${ARGN})
  add_library(shatter_${name} ${ARG_SOURCES})
  add_library(shatter::${name} ALIAS shatter_${name})
  set_target_properties(shatter_${name} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(shatter_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(IS_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/internal)
    target_include_directories(shatter_${name} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/internal>)
  endif()
  target_link_libraries(shatter_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  foreach(dep IN LISTS ARG_BUILD_DEPS)
    target_link_libraries(shatter_${name} PUBLIC $<BUILD_INTERFACE:${dep}>)
  endforeach()
  # The headers use C++20 (defaulted comparisons, std::span): a consumer that links
  # the installed target gets the language level with it, whatever it sets itself.
  target_compile_features(shatter_${name} PUBLIC cxx_std_20)
  shatter_warnings(shatter_${name})
  if(ARG_INTERNAL)
    return()
  endif()
  install(TARGETS shatter_${name} EXPORT shatterTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

function(shatter_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion)
  if(SHATTER_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
