# Bullet 3.24 as the imported target shatter::bullet, for the runtime. The build
# and an installed shatterConfig.cmake both find it with this file (installed
# beside the config); running it twice does nothing.
#
# Debian's Bullet ships two builds side by side: single precision
# (libBulletDynamics.so, what pkg-config's `bullet` names) and double precision
# (libBulletDynamics-float64.so, which BulletConfig-float64.cmake names). The
# runtime uses the double one, so the nodes' exact mass properties and the
# momentum of every split survive to 1e-12 instead of 1e-6; every file that
# includes a Bullet header must then see BT_USE_DOUBLE_PRECISION, which the
# imported target carries. Its include folder is marked SYSTEM (imported targets'
# are), so Bullet's own warnings stay out of our -Wall builds.
if(NOT TARGET shatter::bullet)
  find_path(SHATTER_BULLET_INCLUDE_DIR btBulletDynamicsCommon.h PATH_SUFFIXES bullet)
  set(shatter_bullet_libraries)
  foreach(component BulletDynamics BulletCollision LinearMath)
    find_library(SHATTER_BULLET_${component}_LIBRARY NAMES ${component}-float64)
    if(NOT SHATTER_BULLET_${component}_LIBRARY)
      message(FATAL_ERROR "shatter's runtime needs Bullet's double-precision build: ${component}-float64 "
                          "not found (Debian: apt-get install libbullet-dev)")
    endif()
    list(APPEND shatter_bullet_libraries ${SHATTER_BULLET_${component}_LIBRARY})
  endforeach()
  if(NOT SHATTER_BULLET_INCLUDE_DIR)
    message(FATAL_ERROR "shatter's runtime needs Bullet's headers (Debian: apt-get install libbullet-dev)")
  endif()
  add_library(shatter::bullet INTERFACE IMPORTED)
  set_target_properties(shatter::bullet PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${SHATTER_BULLET_INCLUDE_DIR}"
    INTERFACE_COMPILE_DEFINITIONS BT_USE_DOUBLE_PRECISION
    INTERFACE_LINK_LIBRARIES "${shatter_bullet_libraries}")
endif()
