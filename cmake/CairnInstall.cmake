# Installing cairn as a package that other CMake projects, pkg-config and Debian can use (issue 39;
# docs/use_from_cpp.md).
#
# cairn_install_module(<module>)
#   Called at the end of src/cairn/<module>/CMakeLists.txt, after the module's
#   target_link_libraries. Installs cairn_<module> (exported as cairn::<module>) in its own export
#   set, cairn-<module>-targets, so that find_package(cairn COMPONENTS <module>) loads that module
#   and what it needs and nothing else. From the target's link libraries it writes
#     cairn-<module>-dependencies.cmake: the cairn modules and third-party packages the installed
#       target needs first (its INTERFACE_LINK_LIBRARIES: the public links, and for a static
#       library also the private ones, which it carries as $<LINK_ONLY:...>);
#     cairn-<module>.pc: the same for pkg-config (Requires / Requires.private / Libs.private).
#   A link library the table below does not know stops the configuration, naming it: add it there.
#
# cairn_install_package()
#   Once, at the end of the top-level CMakeLists.txt: the headers, cairnConfig.cmake,
#   cairnConfigVersion.cmake and the Find modules the config needs.
include_guard(GLOBAL)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CAIRN_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/cairn")
set(CAIRN_INSTALL_PKGCONFIGDIR "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
set(_CAIRN_INSTALL_DIR "${CMAKE_CURRENT_LIST_DIR}")

# ---------------------------------------------------------------------------------------------
# The third-party packages the modules link, one row each: the link item(s) in the modules'
# CMakeLists, how cairnConfig.cmake finds the package, and what pkg-config needs (the name of its
# .pc file, or linker flags when Debian 12 ships none). pkg-config targets (PkgConfig::<PREFIX>
# from pkg_check_modules) need no row: the config recreates them with the same prefix and module.
#
#   package        link item                       find (in cairnConfig.cmake)                                    pkg-config
set(_CAIRN_PACKAGES
  "Eigen3        | Eigen3::Eigen                 | find_dependency(Eigen3 3.4 NO_MODULE)                            | eigen3"
  "nlohmann_json | nlohmann_json::nlohmann_json  | find_dependency(nlohmann_json 3.10)                              | nlohmann_json"
  "ZLIB          | ZLIB::ZLIB                    | find_dependency(ZLIB)                                            | zlib"
  "BZip2         | BZip2::BZip2                  | find_dependency(BZip2)                                           | -lbz2"
  "LibLZMA       | LibLZMA::LibLZMA              | find_dependency(LibLZMA)                                         | liblzma"
  "yaml-cpp      | yaml-cpp                      | find_dependency(yaml-cpp)                                        | yaml-cpp"
  "SQLite3       | SQLite::SQLite3               | find_dependency(SQLite3)                                         | sqlite3"
  "PNG           | PNG::PNG                      | find_dependency(PNG)                                             | libpng"
  "JPEG          | JPEG::JPEG                    | find_dependency(JPEG)                                            | libjpeg"
  "TBB           | TBB::tbb                      | find_dependency(TBB)                                             | tbb"
  "CHOLMOD       | CHOLMOD::CHOLMOD              | find_dependency(CHOLMOD)                                         | -lcholmod -lamd -lcolamd -lcamd -lccolamd -lsuitesparseconfig"
  "OpenMP        | OpenMP::OpenMP_CXX            | find_dependency(OpenMP COMPONENTS CXX)                           | -fopenmp"
  "GeographicLib | GeographicLib::GeographicLib  | find_dependency(GeographicLib)                                   | geographiclib"
  "nanoflann     | nanoflann::nanoflann          | find_dependency(nanoflann)                                       | nanoflann"
  "OpenCV        | opencv_*                      | find_dependency(OpenCV 4 COMPONENTS core imgproc features2d calib3d video) | opencv4"
  "dl            | dl                            |                                                                  | -ldl"
)

# Splits the table once into _CAIRN_PACKAGE_NAMES and, per package P, _CAIRN_PACKAGE_<P>_ITEM,
# _FIND, _PC.
function(_cairn_read_package_table)
  set(names "")
  foreach(row IN LISTS _CAIRN_PACKAGES)
    string(REPLACE "|" ";" fields "${row}")
    set(parsed "")
    foreach(field IN LISTS fields)
      string(STRIP "${field}" field)
      list(APPEND parsed "${field}")
    endforeach()
    list(GET parsed 0 name)
    list(GET parsed 1 item)
    list(GET parsed 2 find)
    list(GET parsed 3 pc)
    list(APPEND names "${name}")
    set(_CAIRN_PACKAGE_${name}_ITEM "${item}" PARENT_SCOPE)
    set(_CAIRN_PACKAGE_${name}_FIND "${find}" PARENT_SCOPE)
    set(_CAIRN_PACKAGE_${name}_PC "${pc}" PARENT_SCOPE)
  endforeach()
  set(_CAIRN_PACKAGE_NAMES "${names}" PARENT_SCOPE)
endfunction()
_cairn_read_package_table()

# What a link item is: "cairn:<module>", "pkg-config:<PREFIX>=<module>", or a package of the table.
function(_cairn_classify_link item out)
  if(item MATCHES "^cairn::(.+)$")
    set(${out} "cairn:${CMAKE_MATCH_1}" PARENT_SCOPE)
    return()
  endif()
  if(item MATCHES "^PkgConfig::(.+)$")
    set(prefix "${CMAKE_MATCH_1}")
    if(NOT ${prefix}_MODULE_NAME)
      message(FATAL_ERROR "cairn_install_module: ${item} was not made by pkg_check_modules(${prefix} ... <one module>)")
    endif()
    set(${out} "pkg-config:${prefix}=${${prefix}_MODULE_NAME}" PARENT_SCOPE)
    return()
  endif()
  foreach(name IN LISTS _CAIRN_PACKAGE_NAMES)
    string(REPLACE "*" ".*" pattern "^${_CAIRN_PACKAGE_${name}_ITEM}$")
    if(item MATCHES "${pattern}")
      set(${out} "${name}" PARENT_SCOPE)
      return()
    endif()
  endforeach()
  message(FATAL_ERROR "cairn_install_module: the link library '${item}' is not in the package table of "
                      "cmake/CairnInstall.cmake: add a row saying how an installed cairn finds it")
endfunction()

# The link items of `target`: `public` (its usage requirements) and `private` (the rest).
# `needed` is what a consumer of the installed target must be given: INTERFACE_LINK_LIBRARIES,
# $<LINK_ONLY:x> unwrapped (a static library's private links).
function(_cairn_link_items target public private needed)
  get_target_property(interface ${target} INTERFACE_LINK_LIBRARIES)
  get_target_property(all ${target} LINK_LIBRARIES)
  if(NOT interface)
    set(interface "")
  endif()
  if(NOT all)
    set(all "")
  endif()
  set(pub "")
  set(need "")
  foreach(item IN LISTS interface)
    if(item MATCHES "^\\$<LINK_ONLY:(.+)>$")
      list(APPEND need "${CMAKE_MATCH_1}")
    elseif(item MATCHES "^\\$<")
      message(FATAL_ERROR "cairn_install_module: ${target} links '${item}', a generator expression this helper does not read")
    else()
      list(APPEND pub "${item}")
      list(APPEND need "${item}")
    endif()
  endforeach()
  set(priv "")
  foreach(item IN LISTS all)
    if(NOT item IN_LIST pub)
      list(APPEND priv "${item}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES pub)
  list(REMOVE_DUPLICATES priv)
  list(REMOVE_DUPLICATES need)
  set(${public} "${pub}" PARENT_SCOPE)
  set(${private} "${priv}" PARENT_SCOPE)
  set(${needed} "${need}" PARENT_SCOPE)
endfunction()

# Link items -> cairn modules and packages (classified, deduplicated, in order).
function(_cairn_classify_links items modules packages)
  set(mods "")
  set(pkgs "")
  foreach(item IN LISTS items)
    _cairn_classify_link("${item}" kind)
    if(kind MATCHES "^cairn:(.+)$")
      list(APPEND mods "${CMAKE_MATCH_1}")
    else()
      list(APPEND pkgs "${kind}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES mods)
  list(REMOVE_DUPLICATES pkgs)
  set(${modules} "${mods}" PARENT_SCOPE)
  set(${packages} "${pkgs}" PARENT_SCOPE)
endfunction()

# pkg-config fields of a list of cairn modules and packages: `requires` (.pc names) and `libs`.
function(_cairn_pc_fields modules packages requires libs)
  set(req "")
  set(flags "")
  foreach(module IN LISTS modules)
    list(APPEND req "cairn-${module}")
  endforeach()
  foreach(package IN LISTS packages)
    if(package MATCHES "^pkg-config:[^=]+=(.+)$")
      list(APPEND req "${CMAKE_MATCH_1}")
    elseif(_CAIRN_PACKAGE_${package}_PC MATCHES "^-")
      list(APPEND flags "${_CAIRN_PACKAGE_${package}_PC}")
    else()
      list(APPEND req "${_CAIRN_PACKAGE_${package}_PC}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES req)
  list(JOIN req ", " req)
  list(JOIN flags " " flags)
  set(${requires} "${req}" PARENT_SCOPE)
  set(${libs} "${flags}" PARENT_SCOPE)
endfunction()

function(cairn_install_module module)
  set(target cairn_${module})
  if(NOT TARGET ${target})
    message(FATAL_ERROR "cairn_install_module(${module}): no target ${target}")
  endif()
  set_target_properties(${target} PROPERTIES
    EXPORT_NAME ${module}
    VERSION ${PROJECT_VERSION}
    # Before 1.0 the ABI may change with every minor version.
    SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  install(TARGETS ${target} EXPORT cairn-${module}-targets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(EXPORT cairn-${module}-targets NAMESPACE cairn:: DESTINATION ${CAIRN_INSTALL_CMAKEDIR})

  _cairn_link_items(${target} public private needed)

  # What find_package(cairn COMPONENTS <module>) loads before cairn-<module>-targets.cmake.
  _cairn_classify_links("${needed}" needed_modules needed_packages)
  set(text "# What cairn::${module} needs before cairn-${module}-targets.cmake can be loaded: the cairn\n")
  string(APPEND text "# modules and third-party packages it links (a static library: its private links too).\n")
  string(APPEND text "# Generated by cmake/CairnInstall.cmake; read by cairnConfig.cmake.\n")
  string(APPEND text "set(cairn_${module}_DEPENDS \"${needed_modules}\")\n")
  string(APPEND text "set(cairn_${module}_PACKAGES \"${needed_packages}\")\n")
  set(dependencies "${PROJECT_BINARY_DIR}/cairn-package/cairn-${module}-dependencies.cmake")
  file(CONFIGURE OUTPUT "${dependencies}" CONTENT "${text}" @ONLY)
  install(FILES "${dependencies}" DESTINATION ${CAIRN_INSTALL_CMAKEDIR})

  # pkg-config: the public links are Requires, the private ones Requires.private / Libs.private.
  _cairn_classify_links("${public}" public_modules public_packages)
  _cairn_classify_links("${private}" private_modules private_packages)
  _cairn_pc_fields("${public_modules}" "${public_packages}" CAIRN_PC_REQUIRES CAIRN_PC_LIBS)
  _cairn_pc_fields("${private_modules}" "${private_packages}" CAIRN_PC_REQUIRES_PRIVATE CAIRN_PC_LIBS_PRIVATE)
  set(CAIRN_PC_MODULE ${module})
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "SHARED_LIBRARY")
    set(CAIRN_PC_KIND shared)
  else()
    set(CAIRN_PC_KIND static)
  endif()
  if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
    message(FATAL_ERROR "cairn: CMAKE_INSTALL_LIBDIR must be relative to the prefix (the .pc files find the prefix from their own place)")
  endif()
  file(RELATIVE_PATH CAIRN_PC_PREFIX "/prefix/${CAIRN_INSTALL_PKGCONFIGDIR}" "/prefix")
  string(REGEX REPLACE "/$" "" CAIRN_PC_PREFIX "${CAIRN_PC_PREFIX}")
  configure_file("${_CAIRN_INSTALL_DIR}/cairn-module.pc.in" "${PROJECT_BINARY_DIR}/cairn-package/cairn-${module}.pc" @ONLY)
  install(FILES "${PROJECT_BINARY_DIR}/cairn-package/cairn-${module}.pc" DESTINATION ${CAIRN_INSTALL_PKGCONFIGDIR})

  set_property(GLOBAL APPEND PROPERTY CAIRN_INSTALLED_MODULES ${module})
endfunction()

# cairnConfig.cmake's `_cairn_find_package(<package>)`: one branch per row of the table.
function(_cairn_find_package_branches out)
  set(text "")
  set(keyword "if")
  foreach(name IN LISTS _CAIRN_PACKAGE_NAMES)
    string(APPEND text "    ${keyword}(\"\${_cairn_package}\" STREQUAL \"${name}\")\n")
    if(_CAIRN_PACKAGE_${name}_FIND)
      string(APPEND text "      ${_CAIRN_PACKAGE_${name}_FIND}\n")
    else()
      string(APPEND text "      # nothing to find: a system library named on the link line\n")
    endif()
    set(keyword "elseif")
  endforeach()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

function(cairn_install_package)
  get_property(CAIRN_MODULES GLOBAL PROPERTY CAIRN_INSTALLED_MODULES)

  # Every header of every module, as "cairn/<module>/<name>.hpp" under include/. Not the CLI's
  # (they belong to the two executables) and not vslam/slam_state.hpp (internal to vslam's .cpp
  # files; it includes TBB and the back end, which cairn::vslam links privately).
  install(DIRECTORY "${PROJECT_SOURCE_DIR}/src/cairn" DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
    FILES_MATCHING PATTERN "*.hpp"
    PATTERN "cli" EXCLUDE
    PATTERN "slam_state.hpp" EXCLUDE)

  _cairn_find_package_branches(CAIRN_FIND_PACKAGE_BRANCHES)
  if(BUILD_SHARED_LIBS)
    set(CAIRN_LIBRARY_KIND shared)
  else()
    set(CAIRN_LIBRARY_KIND static)
  endif()
  configure_package_config_file("${_CAIRN_INSTALL_DIR}/cairnConfig.cmake.in"
    "${PROJECT_BINARY_DIR}/cairn-package/cairnConfig.cmake"
    INSTALL_DESTINATION ${CAIRN_INSTALL_CMAKEDIR})
  # Before 1.0, 0.1.x is not compatible with 0.2.
  write_basic_package_version_file("${PROJECT_BINARY_DIR}/cairn-package/cairnConfigVersion.cmake"
    VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
  install(FILES
    "${PROJECT_BINARY_DIR}/cairn-package/cairnConfig.cmake"
    "${PROJECT_BINARY_DIR}/cairn-package/cairnConfigVersion.cmake"
    # Debian 12 ships neither as a CMake package; the config puts this folder on CMAKE_MODULE_PATH.
    "${PROJECT_SOURCE_DIR}/cmake/FindCHOLMOD.cmake"
    "${PROJECT_SOURCE_DIR}/cmake/FindGeographicLib.cmake"
    DESTINATION ${CAIRN_INSTALL_CMAKEDIR})

  install(FILES "${PROJECT_SOURCE_DIR}/README.md" DESTINATION ${CMAKE_INSTALL_DOCDIR})
  install(DIRECTORY "${PROJECT_SOURCE_DIR}/docs/" DESTINATION ${CMAKE_INSTALL_DOCDIR})
endfunction()

# Man pages from `--help` with Debian's help2man (cairn.1 and one per command, cairn-slam3d.1, ...),
# made when `cairn` is built and installed to share/man/man1. Without help2man: none, said once.
function(cairn_add_man_pages)
  find_program(HELP2MAN_EXECUTABLE help2man)
  mark_as_advanced(HELP2MAN_EXECUTABLE)
  if(NOT HELP2MAN_EXECUTABLE)
    message(STATUS "cairn: help2man not found (Debian: help2man): no man pages will be installed")
    return()
  endif()
  set(directory "${PROJECT_BINARY_DIR}/man")
  set(stamp "${directory}/man.stamp")
  add_custom_command(OUTPUT "${stamp}"
    COMMAND ${CMAKE_COMMAND} -DCAIRN=$<TARGET_FILE:cairn> -DHELP2MAN=${HELP2MAN_EXECUTABLE}
            -DOUT=${directory} -DVERSION=${PROJECT_VERSION} -P "${_CAIRN_INSTALL_DIR}/cairn_man_pages.cmake"
    COMMAND ${CMAKE_COMMAND} -E touch "${stamp}"
    DEPENDS cairn cairn-suite "${_CAIRN_INSTALL_DIR}/cairn_man_pages.cmake"
    COMMENT "Man pages from cairn --help (help2man)"
    VERBATIM)
  add_custom_target(cairn_man_pages ALL DEPENDS "${stamp}")
  install(DIRECTORY "${directory}/" DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 FILES_MATCHING PATTERN "*.1.gz")
endfunction()
