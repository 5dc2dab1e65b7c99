# `make package` (cpack -G DEB): one Debian package, cairn_<version>_<arch>.deb, with everything
# `cmake --install` installs under /usr: `cairn` and `cairn-suite`, the man pages and docs, and the
# development files (headers, libraries, cairnConfig.cmake, pkg-config files). One package rather
# than cairn + cairn-dev: cairn's libraries are static by default, so there is no runtime library
# package to split off.
#
# Depends: what the programs (and, with -DBUILD_SHARED_LIBS=ON, the libraries) are linked against,
# as dpkg-shlibdeps computes it from the ELF files and the installed packages' symbols files (exact
# package names and minimum versions; nothing forgotten when a module gains a library). Without
# dpkg-shlibdeps (dpkg-dev), the list below, read off `ldd cairn-suite` on Debian 12.
# Suggests: the -dev packages a program built against the development files needs
# (cairnConfig.cmake finds them with find_dependency); `scripts/install_deps.sh` installs them all.
set(CPACK_GENERATOR "DEB")
set(CPACK_PACKAGE_NAME "cairn")
set(CPACK_PACKAGE_VENDOR "cairn")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "SLAM library and command line that tell you how good their answer is")
set(CPACK_PACKAGE_DESCRIPTION "cairn is a SLAM library and command-line tool in C++20: pose-graph optimisation \
with certificates, trajectory evaluation as evo and the KITTI devkit compute it, 2D and 3D LiDAR SLAM, \
visual SLAM, IMU and GNSS. This package holds the `cairn` command, its man pages and documentation, and \
the development files: headers, libraries, a CMake package (find_package(cairn)) and pkg-config files.")
set(CPACK_PACKAGING_INSTALL_PREFIX "/usr")
set(CPACK_DEBIAN_FILE_NAME "DEB-DEFAULT")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "cairn developers <cairn@localhost>")
set(CPACK_DEBIAN_PACKAGE_SECTION "science")
set(CPACK_DEBIAN_PACKAGE_PRIORITY "optional")

find_program(CAIRN_DPKG_SHLIBDEPS dpkg-shlibdeps)
mark_as_advanced(CAIRN_DPKG_SHLIBDEPS)
if(CAIRN_DPKG_SHLIBDEPS)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
else()
  message(STATUS "cairn: dpkg-shlibdeps not found (Debian: dpkg-dev): `make package` writes Debian 12's dependency list")
  set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "libc6, libstdc++6, libgcc-s1, libgomp1, libcholmod3, libamd2, libcolamd2, libcamd2, libccolamd2, \
libsuitesparseconfig5, libtbb12, libyaml-cpp0.7, zlib1g, libbz2-1.0, liblzma5, liblz4-1, libzstd1, \
libsqlite3-0, libpng16-16, libjpeg62-turbo, libcairo2, libgeographiclib23, libopencv-core406, \
libopencv-imgproc406, libopencv-features2d406, libopencv-calib3d406, libopencv-video406")
endif()
# The Python package (python/): an extension module for this Python version (its ABI tag is in
# the file name), which imports numpy. dpkg-shlibdeps finds its libraries, not the interpreter.
if(CAIRN_BUILD_PYTHON)
  math(EXPR next_minor "${Python_VERSION_MINOR} + 1")
  set(python_depends "python3 (>= ${Python_VERSION_MAJOR}.${Python_VERSION_MINOR}), \
python3 (<< ${Python_VERSION_MAJOR}.${next_minor}), python3-numpy")
  if(CPACK_DEBIAN_PACKAGE_DEPENDS)
    string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", ${python_depends}")
  else()
    set(CPACK_DEBIAN_PACKAGE_DEPENDS "${python_depends}")
  endif()
endif()
set(CPACK_DEBIAN_PACKAGE_SUGGESTS
  "libeigen3-dev, nlohmann-json3-dev, libsuitesparse-dev, libtbb-dev, libyaml-cpp-dev, zlib1g-dev, \
libbz2-dev, liblzma-dev, liblz4-dev, libzstd-dev, libsqlite3-dev, libpng-dev, libjpeg-dev, libcairo2-dev, \
libgeographiclib-dev, libnanoflann-dev, libopencv-dev, pkg-config, cmake")

include(CPack)
