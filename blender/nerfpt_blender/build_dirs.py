"""Build folders where the nerfpt binary may be (after PATH). scripts/package_blender_addon.sh writes the
packaging checkout's build folder into the copy of this file that goes into the zip."""

BUILD_DIRS = []
