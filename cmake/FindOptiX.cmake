# The OptiX SDK headers (NVIDIA's optix-dev: include/optix.h). The OptiX runtime itself ships in the NVIDIA
# driver and is loaded at run time, so nothing is linked. The headers may not be redistributed: they are put
# into the git-ignored .optix/ by ../shared/scripts/get-optix.sh. Sets OptiX_FOUND and OptiX_INCLUDE_DIR.
set(OptiX_INSTALL_DIR "${PROJECT_SOURCE_DIR}/.optix" CACHE PATH "Folder holding include/optix.h (OptiX SDK headers)")
find_path(OptiX_INCLUDE_DIR optix.h PATHS "${OptiX_INSTALL_DIR}/include" NO_DEFAULT_PATH)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OptiX REQUIRED_VARS OptiX_INCLUDE_DIR)
