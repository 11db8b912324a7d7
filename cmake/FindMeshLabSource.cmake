# Finds the MeshLab source tree unpacked by scripts/setup (`apt-get source
# meshlab=<installed version>` into .deps/meshlab-source/), which provides the vcglib and
# MeshLab headers of exactly the installed MeshLab. Debian ships no headers.
#
# Sets MESHLAB_SOURCE_DIR, VCGLIB_DIR, MESHLAB_VERSION, and the imported
# target meshmend::vcglib (header-only). Override with -DMESHLAB_SOURCE_DIR=...
if(NOT MESHLAB_SOURCE_DIR OR NOT EXISTS "${MESHLAB_SOURCE_DIR}/ML_VERSION")
  unset(MESHLAB_SOURCE_DIR CACHE)
  unset(MESHLAB_SOURCE_DIR)
  file(GLOB _meshlab_candidates "${CMAKE_SOURCE_DIR}/.deps/meshlab-source/meshlab-*")
  list(SORT _meshlab_candidates)
  foreach(_dir ${_meshlab_candidates})
    if(IS_DIRECTORY "${_dir}/src/common" AND IS_DIRECTORY "${_dir}/vcglib/vcg")
      set(MESHLAB_SOURCE_DIR "${_dir}")
    endif()
  endforeach()
endif()
set(MESHLAB_SOURCE_DIR "${MESHLAB_SOURCE_DIR}" CACHE PATH "Unpacked MeshLab source (apt-get source meshlab)")

if(MESHLAB_SOURCE_DIR AND EXISTS "${MESHLAB_SOURCE_DIR}/ML_VERSION")
  file(READ "${MESHLAB_SOURCE_DIR}/ML_VERSION" MESHLAB_VERSION)
  string(STRIP "${MESHLAB_VERSION}" MESHLAB_VERSION)
  # vcglib sits beside src/ in Debian's 2020.09 tree, inside it in upstream 2022.02.
  foreach(_vcg "${MESHLAB_SOURCE_DIR}/vcglib" "${MESHLAB_SOURCE_DIR}/src/vcglib")
    if(NOT VCGLIB_DIR AND IS_DIRECTORY "${_vcg}/vcg")
      set(VCGLIB_DIR "${_vcg}")
    endif()
  endforeach()
endif()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(MeshLabSource
  REQUIRED_VARS MESHLAB_SOURCE_DIR VCGLIB_DIR MESHLAB_VERSION
  FAIL_MESSAGE "MeshLab source not found: run scripts/setup (it unpacks `apt-get source meshlab` into .deps/) or pass -DMESHLAB_SOURCE_DIR=...")

if(MeshLabSource_FOUND AND NOT TARGET meshmend::vcglib)
  add_library(meshmend::vcglib INTERFACE IMPORTED)
  set_target_properties(meshmend::vcglib PROPERTIES
    INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${VCGLIB_DIR}"
    INTERFACE_INCLUDE_DIRECTORIES "${VCGLIB_DIR}")
endif()
