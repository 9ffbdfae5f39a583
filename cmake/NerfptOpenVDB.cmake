# OpenVDB (and the header-only NanoVDB that ships beside it) as one small imported target, nerfpt::openvdb.
# Debian's FindOpenVDB.cmake brings its own FindTBB/FindOpenEXR that clash with the config packages we use, so
# we find the header and the shared library directly; libopenvdb.so carries its own Blosc/Boost/TBB links.
find_path(OPENVDB_INCLUDE_DIR openvdb/openvdb.h REQUIRED)
find_path(NANOVDB_INCLUDE_DIR nanovdb/NanoVDB.h REQUIRED)
find_library(OPENVDB_LIBRARY NAMES openvdb REQUIRED)
find_path(IMATH_INCLUDE_DIR Imath/half.h REQUIRED)  # OpenVDB's half type

add_library(nerfpt::openvdb INTERFACE IMPORTED)
# SYSTEM: OpenVDB's headers are not clean under our -Wall -Wextra -Werror.
set_target_properties(nerfpt::openvdb PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${OPENVDB_INCLUDE_DIR};${NANOVDB_INCLUDE_DIR};${IMATH_INCLUDE_DIR}"
    INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${OPENVDB_INCLUDE_DIR};${NANOVDB_INCLUDE_DIR};${IMATH_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${OPENVDB_LIBRARY};TBB::tbb")
message(STATUS "OpenVDB: ${OPENVDB_LIBRARY} (headers ${OPENVDB_INCLUDE_DIR}, NanoVDB ${NANOVDB_INCLUDE_DIR})")
