# Finds libnova (Debian libnova-dev), which ships no CMake package and no pkg-config file.
#
#   find_package(libnova [REQUIRED])   ->  libnova_FOUND, target libnova::libnova
#
# atmo's build uses it, and the installed package config (atmoConfig.cmake) runs it again from
# its own folder, because a static libatmo.a needs libnova at the consumer's link.
find_path(LIBNOVA_INCLUDE_DIR libnova/solar.h)
find_library(LIBNOVA_LIBRARY nova)
mark_as_advanced(LIBNOVA_INCLUDE_DIR LIBNOVA_LIBRARY)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(libnova REQUIRED_VARS LIBNOVA_LIBRARY LIBNOVA_INCLUDE_DIR)

if(libnova_FOUND AND NOT TARGET libnova::libnova)
  add_library(libnova::libnova UNKNOWN IMPORTED)
  set_target_properties(libnova::libnova PROPERTIES
    IMPORTED_LOCATION "${LIBNOVA_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${LIBNOVA_INCLUDE_DIR}")
endif()
