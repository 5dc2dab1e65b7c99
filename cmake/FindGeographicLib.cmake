# FindGeographicLib: GeographicLib (Debian: libgeographiclib-dev). Debian 12's 2.1.2 ships no
# CMake config package, only /usr/share/cmake/geographiclib/FindGeographicLib.cmake, which is not on
# CMake's module path and sets variables, not a target. This finds the header and library and
# defines GeographicLib::GeographicLib.
find_path(GeographicLib_INCLUDE_DIR GeographicLib/LocalCartesian.hpp)
find_library(GeographicLib_LIBRARY NAMES GeographicLib Geographic)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(GeographicLib REQUIRED_VARS GeographicLib_INCLUDE_DIR GeographicLib_LIBRARY)

if(GeographicLib_FOUND AND NOT TARGET GeographicLib::GeographicLib)
  add_library(GeographicLib::GeographicLib UNKNOWN IMPORTED)
  set_target_properties(GeographicLib::GeographicLib PROPERTIES
    IMPORTED_LOCATION "${GeographicLib_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${GeographicLib_INCLUDE_DIR}")
endif()
mark_as_advanced(GeographicLib_INCLUDE_DIR GeographicLib_LIBRARY)
