#!/usr/bin/env bash
# Installs the C interface under a prefix, the way C and C++ builds find libraries:
#   PREFIX/include/mpm_gimp.h
#   PREFIX/lib/libmpm_gimp.a, libmpm_gimp.so.X.Y.Z (soname libmpm_gimp.so.X.Y) and its links
#   PREFIX/lib/pkgconfig/mpm-gimp.pc                      (pkg-config --cflags --libs mpm-gimp)
#   PREFIX/lib/cmake/mpm-gimp/mpm-gimpConfig*.cmake       (find_package(mpm-gimp))
#
# usage: ffi/install.sh PREFIX [BUILT]
# BUILT is a directory holding libmpm_gimp.a and libmpm_gimp.so already built; without it the
# script runs `cargo build --release -p mpm-gimp-ffi` and takes target/release. Run from the
# repository root. The f64 library needs hosts compiled with -DMPM_GIMP_F64.
set -euo pipefail
prefix=${1:?usage: ffi/install.sh PREFIX [BUILT]}
built=${2:-}
version=$(sed -n 's/^version = "\(.*\)"$/\1/p' ffi/Cargo.toml | head -n 1)
major_minor=${version%.*}
if [ -z "$built" ]; then
    cargo build --release -p mpm-gimp-ffi
    built=target/release
fi
mkdir -p "$prefix"
prefix=$(cd "$prefix" && pwd)
lib="$prefix/lib"
install -d "$prefix/include" "$lib/pkgconfig" "$lib/cmake/mpm-gimp"
install -m 644 ffi/include/mpm_gimp.h "$prefix/include/"
install -m 644 "$built/libmpm_gimp.a" "$lib/"
install -m 755 "$built/libmpm_gimp.so" "$lib/libmpm_gimp.so.$version"
ln -sf "libmpm_gimp.so.$version" "$lib/libmpm_gimp.so.$major_minor"
ln -sf "libmpm_gimp.so.$major_minor" "$lib/libmpm_gimp.so"

# What a static link of a Rust library needs from the system besides libc.
system_libs="-lpthread -ldl -lm"

cat > "$lib/pkgconfig/mpm-gimp.pc" <<PC
prefix=$prefix
libdir=\${prefix}/lib
includedir=\${prefix}/include

Name: mpm-gimp
Description: Allocation-free GIMP material point kernel, C interface
Version: $version
Cflags: -I\${includedir}
Libs: -L\${libdir} -lmpm_gimp
Libs.private: $system_libs
PC

cat > "$lib/cmake/mpm-gimp/mpm-gimpConfig.cmake" <<CMAKE
# mpm-gimp $version: the imported targets mpm-gimp::mpm-gimp (shared library) and
# mpm-gimp::static (static library), both with the header's directory.
get_filename_component(_mpm_gimp_prefix "\${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
if(NOT TARGET mpm-gimp::mpm-gimp)
  add_library(mpm-gimp::mpm-gimp SHARED IMPORTED)
  set_target_properties(mpm-gimp::mpm-gimp PROPERTIES
    IMPORTED_LOCATION "\${_mpm_gimp_prefix}/lib/libmpm_gimp.so.$version"
    IMPORTED_SONAME "libmpm_gimp.so.$major_minor"
    INTERFACE_INCLUDE_DIRECTORIES "\${_mpm_gimp_prefix}/include")
  add_library(mpm-gimp::static STATIC IMPORTED)
  set_target_properties(mpm-gimp::static PROPERTIES
    IMPORTED_LOCATION "\${_mpm_gimp_prefix}/lib/libmpm_gimp.a"
    INTERFACE_INCLUDE_DIRECTORIES "\${_mpm_gimp_prefix}/include"
    INTERFACE_LINK_LIBRARIES "pthread;dl;m")
endif()
unset(_mpm_gimp_prefix)
CMAKE

cat > "$lib/cmake/mpm-gimp/mpm-gimpConfigVersion.cmake" <<CMAKE
# Before 1.0 a minor version may break the ABI: a request for X.Y matches X.Y.* at or above it.
set(PACKAGE_VERSION "$version")
set(PACKAGE_VERSION_COMPATIBLE FALSE)
if(NOT PACKAGE_FIND_VERSION)
  set(PACKAGE_VERSION_COMPATIBLE TRUE)
elseif("\${PACKAGE_FIND_VERSION_MAJOR}.\${PACKAGE_FIND_VERSION_MINOR}" STREQUAL "$major_minor"
       AND NOT PACKAGE_FIND_VERSION VERSION_GREATER PACKAGE_VERSION)
  set(PACKAGE_VERSION_COMPATIBLE TRUE)
endif()
if(PACKAGE_FIND_VERSION STREQUAL PACKAGE_VERSION)
  set(PACKAGE_VERSION_EXACT TRUE)
endif()
CMAKE
echo "installed mpm-gimp $version under $prefix"
