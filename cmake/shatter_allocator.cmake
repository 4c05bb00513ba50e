# The executables (the `shatter` command and the benchmarks) allocate through
# jemalloc (cli/jemalloc_options.cpp says why, and why not with huge pages). The
# sanitizers and libFuzzer replace malloc themselves, so there the C library's
# allocator stays, as it does with -DSHATTER_JEMALLOC=OFF.
if(SHATTER_SANITIZE OR SHATTER_BUILD_FUZZERS)
  set(shatter_jemalloc_default OFF)
else()
  set(shatter_jemalloc_default ON)
endif()
option(SHATTER_JEMALLOC "Link the executables with jemalloc"
       ${shatter_jemalloc_default})
if(SHATTER_JEMALLOC)
  pkg_check_modules(jemalloc REQUIRED IMPORTED_TARGET jemalloc)
endif()

# Gives `target` (an executable) jemalloc and its options, and large arrays on
# huge pages (cli/huge_page_arrays.cpp), when SHATTER_JEMALLOC is on.
function(shatter_use_jemalloc target)
  if(SHATTER_JEMALLOC)
    target_sources(${target} PRIVATE ${PROJECT_SOURCE_DIR}/cli/jemalloc_options.cpp
                                      ${PROJECT_SOURCE_DIR}/cli/huge_page_arrays.cpp)
    # Its own translation unit: it defines operator new, whatever a unity build
    # would put beside it.
    set_source_files_properties(${PROJECT_SOURCE_DIR}/cli/huge_page_arrays.cpp PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
    target_link_libraries(${target} PRIVATE PkgConfig::jemalloc)
    # cli/huge_page_objects.cpp talks to jemalloc only where it is linked.
    target_compile_definitions(${target} PRIVATE SHATTER_WITH_JEMALLOC=1)
  endif()
endfunction()
