#!/usr/bin/env bash
# Installs the C interface under a prefix, the way C and C++ builds find libraries (ffi/README.md).
# The single-precision library (mpm_real = float):
#   PREFIX/include/mpm_gimp.h
#   PREFIX/lib/libmpm_gimp.a, libmpm_gimp.so.X.Y.Z (soname libmpm_gimp.so.X.Y) and its links
#   PREFIX/lib/pkgconfig/mpm-gimp.pc          (pkg-config --cflags --libs mpm-gimp)
#   PREFIX/lib/cmake/mpm-gimp/                (find_package(mpm-gimp): mpm-gimp::mpm-gimp,
#                                              mpm-gimp::static)
# With --f64, the double-precision library (mpm_real = double), under names of its own so that
# it stands beside the other in the same prefix:
#   PREFIX/include/mpm_gimp.h                 (the same header: hosts define MPM_GIMP_F64)
#   PREFIX/lib/libmpm_gimp_f64.a, libmpm_gimp_f64.so.X.Y.Z (soname libmpm_gimp_f64.so.X.Y)
#   PREFIX/lib/pkgconfig/mpm-gimp-f64.pc      (its Cflags carry -DMPM_GIMP_F64)
#   PREFIX/lib/cmake/mpm-gimp/                (the same package: mpm-gimp::f64,
#                                              mpm-gimp::f64-static)
# Both in one prefix: run the script once without --f64 and once with it. The pkg-config files
# put the library directory in the program's run path (-Wl,-rpath), so that a program linked
# with them runs without LD_LIBRARY_PATH; CMake does the same for its build tree.
#
# usage: ffi/install.sh [--f64] PREFIX [BUILT]
# BUILT is a directory holding libmpm_gimp.a and libmpm_gimp.so of the precision asked for, as
# cargo names both builds. Without it the script builds them: `cargo build --release -p
# mpm-gimp-ffi` into target/release, or with --f64 `cargo build --release -p mpm-gimp-ffi
# --features f64 --target-dir target/f64` into target/f64/release. Run from the repository root.
set -euo pipefail
usage="usage: ffi/install.sh [--f64] PREFIX [BUILT]"
f64=0
args=()
for arg in "$@"; do
    case $arg in
        --f64) f64=1 ;;
        -h | --help)
            echo "$usage"
            exit 0
            ;;
        -*)
            echo "unknown option $arg; $usage" >&2
            exit 2
            ;;
        *) args+=("$arg") ;;
    esac
done
if [ "${#args[@]}" -lt 1 ] || [ "${#args[@]}" -gt 2 ]; then
    echo "$usage" >&2
    exit 2
fi
prefix=${args[0]}
built=${args[1]:-}
version=$(sed -n 's/^version = "\(.*\)"$/\1/p' ffi/Cargo.toml | head -n 1)
major_minor=${version%.*}

# What differs between the precisions: file names, the pkg-config module, the CMake targets
# and the macro the header reads.
if [ "$f64" -eq 1 ]; then
    precision=f64
    name=mpm_gimp_f64
    module=mpm-gimp-f64
    defines=" -DMPM_GIMP_F64"
    shared_target=mpm-gimp::f64
    static_target=mpm-gimp::f64-static
    cmake_defines='
    INTERFACE_COMPILE_DEFINITIONS "MPM_GIMP_F64"'
    description="double precision"
    if [ -z "$built" ]; then
        cargo build --release -p mpm-gimp-ffi --features f64 --target-dir target/f64
        built=target/f64/release
    fi
else
    precision=f32
    name=mpm_gimp
    module=mpm-gimp
    defines=""
    shared_target=mpm-gimp::mpm-gimp
    static_target=mpm-gimp::static
    cmake_defines=""
    description="single precision"
    if [ -z "$built" ]; then
        cargo build --release -p mpm-gimp-ffi
        built=target/release
    fi
fi
soname="lib$name.so.$major_minor"

# The built libraries must be this version's, of this precision: the shared library carries
# its soname (ffi/build.rs), the static one the precision's symbols.
for file in libmpm_gimp.a libmpm_gimp.so; do
    if [ ! -f "$built/$file" ]; then
        echo "no $built/$file: build the library first (ffi/README.md)" >&2
        exit 1
    fi
done
if ! grep -qF "$soname" "$built/libmpm_gimp.so" ||
    ! grep -qF "mpm_world_def_default_$precision" "$built/libmpm_gimp.a"; then
    echo "$built holds no $precision build of mpm-gimp-ffi $version (soname $soname);" \
        "the f64 library is built with --features f64" >&2
    exit 1
fi

mkdir -p "$prefix"
prefix=$(cd "$prefix" && pwd)
lib="$prefix/lib"
install -d "$prefix/include" "$lib/pkgconfig" "$lib/cmake/mpm-gimp"
install -m 644 ffi/include/mpm_gimp.h "$prefix/include/"
install -m 644 "$built/libmpm_gimp.a" "$lib/lib$name.a"
install -m 755 "$built/libmpm_gimp.so" "$lib/lib$name.so.$version"
ln -sf "lib$name.so.$version" "$lib/$soname"
ln -sf "$soname" "$lib/lib$name.so"

# What a static link of a Rust library needs from the system besides libc.
system_libs="-lpthread -ldl -lm"

cat > "$lib/pkgconfig/$module.pc" <<PC
prefix=$prefix
libdir=\${prefix}/lib
includedir=\${prefix}/include

Name: $module
Description: Allocation-free GIMP material point kernel, C interface, $description
Version: $version
Cflags: -I\${includedir}$defines
Libs: -L\${libdir} -Wl,-rpath,\${libdir} -l$name
Libs.private: $system_libs
PC

# The package: one config that loads the targets of each precision installed beside it.
cat > "$lib/cmake/mpm-gimp/mpm-gimpConfig.cmake" <<'CMAKE'
# mpm-gimp: the imported targets of each precision installed in this prefix (ffi/install.sh),
# each with the header's directory:
#   f32: mpm-gimp::mpm-gimp (shared library), mpm-gimp::static (static library)
#   f64: mpm-gimp::f64 (shared library), mpm-gimp::f64-static (static library); both define
#        MPM_GIMP_F64 for the code that links them.
# The components f32 and f64 ask for a precision: find_package(mpm-gimp 0.10 REQUIRED
# COMPONENTS f64). Without components, the package is found with whatever is installed.
file(GLOB _mpm_gimp_targets "${CMAKE_CURRENT_LIST_DIR}/mpm-gimpTargets-*.cmake")
foreach(_mpm_gimp_file IN LISTS _mpm_gimp_targets)
  include("${_mpm_gimp_file}")
endforeach()
foreach(_mpm_gimp_component IN LISTS mpm-gimp_FIND_COMPONENTS)
  if(NOT mpm-gimp_${_mpm_gimp_component}_FOUND AND mpm-gimp_FIND_REQUIRED_${_mpm_gimp_component})
    set(mpm-gimp_FOUND FALSE)
    set(mpm-gimp_NOT_FOUND_MESSAGE
      "the ${_mpm_gimp_component} library is not installed here (components: f32, f64)")
  endif()
endforeach()
unset(_mpm_gimp_targets)
unset(_mpm_gimp_file)
unset(_mpm_gimp_component)
CMAKE

cat > "$lib/cmake/mpm-gimp/mpm-gimpTargets-$precision.cmake" <<CMAKE
# The $description library of mpm-gimp $version (ffi/install.sh --help).
get_filename_component(_mpm_gimp_prefix "\${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
if(NOT TARGET $shared_target)
  add_library($shared_target SHARED IMPORTED)
  set_target_properties($shared_target PROPERTIES
    IMPORTED_LOCATION "\${_mpm_gimp_prefix}/lib/lib$name.so.$version"
    IMPORTED_SONAME "$soname"
    INTERFACE_INCLUDE_DIRECTORIES "\${_mpm_gimp_prefix}/include"$cmake_defines)
  add_library($static_target STATIC IMPORTED)
  set_target_properties($static_target PROPERTIES
    IMPORTED_LOCATION "\${_mpm_gimp_prefix}/lib/lib$name.a"
    INTERFACE_INCLUDE_DIRECTORIES "\${_mpm_gimp_prefix}/include"$cmake_defines
    INTERFACE_LINK_LIBRARIES "pthread;dl;m")
endif()
set(mpm-gimp_${precision}_FOUND TRUE)
unset(_mpm_gimp_prefix)
CMAKE

cat > "$lib/cmake/mpm-gimp/mpm-gimpConfigVersion.cmake" <<CMAKE
# Before 1.0 a minor version may break the ABI: a request for X.Y matches X.Y.* at or above it.
# Both precisions in one prefix are of one version (install them from one source tree).
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
# The package's version file is this version's: a library of the other precision from another
# version would be found under it.
for other in "$lib"/cmake/mpm-gimp/mpm-gimpTargets-*.cmake; do
    if ! grep -qF "of mpm-gimp $version " "$other"; then
        echo "warning: $other is of another version; install that precision again" >&2
    fi
done
echo "installed mpm-gimp $version ($precision: lib$name, $module.pc, $shared_target) under $prefix"
