# GMP (with its C++ interface, gmpxx) and MPFR as imported targets shatter::gmp,
# shatter::gmpxx and shatter::mpfr. Debian ships no CMake package for them, so the
# build and an installed shatterConfig.cmake both find them with this file (it is
# installed beside the config); running it twice does nothing.
if(NOT TARGET shatter::gmpxx)
  find_path(SHATTER_GMP_INCLUDE_DIR gmpxx.h)
  find_library(SHATTER_GMPXX_LIBRARY gmpxx)
  find_library(SHATTER_GMP_LIBRARY gmp)
  find_library(SHATTER_MPFR_LIBRARY mpfr)
  foreach(found SHATTER_GMP_INCLUDE_DIR SHATTER_GMPXX_LIBRARY SHATTER_GMP_LIBRARY SHATTER_MPFR_LIBRARY)
    if(NOT ${found})
      message(FATAL_ERROR "shatter needs GMP (with gmpxx) and MPFR: ${found} not found "
                          "(Debian: apt-get install libgmp-dev libmpfr-dev)")
    endif()
  endforeach()
  add_library(shatter::gmp UNKNOWN IMPORTED)
  set_target_properties(shatter::gmp PROPERTIES IMPORTED_LOCATION "${SHATTER_GMP_LIBRARY}"
                                                INTERFACE_INCLUDE_DIRECTORIES "${SHATTER_GMP_INCLUDE_DIR}")
  add_library(shatter::gmpxx UNKNOWN IMPORTED)
  set_target_properties(shatter::gmpxx PROPERTIES IMPORTED_LOCATION "${SHATTER_GMPXX_LIBRARY}"
                                                  INTERFACE_LINK_LIBRARIES shatter::gmp)
  add_library(shatter::mpfr UNKNOWN IMPORTED)
  set_target_properties(shatter::mpfr PROPERTIES IMPORTED_LOCATION "${SHATTER_MPFR_LIBRARY}"
                                                 INTERFACE_LINK_LIBRARIES shatter::gmp)
endif()
