# Every dependency comes from Debian packages (scripts/install-deps.sh installs them).
find_package(Threads REQUIRED)
find_package(glm REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(OpenImageIO REQUIRED)
find_package(OpenMesh REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(embree 3 REQUIRED)
# CGAL (header-only in Debian's libcgal-dev) for the light probes' Delaunay tetrahedralisation.
find_package(CGAL REQUIRED)

# tinygltf: Debian ships the single header; we compile its implementation ourselves in
# scenes/src/tinygltf_impl.cpp without stb_image so that textures load through OpenImageIO
# and the fuzzer instruments the parser too.
find_path(TINYGLTF_INCLUDE_DIR tiny_gltf.h REQUIRED)
find_path(STB_INCLUDE_DIR stb_image.h PATH_SUFFIXES stb REQUIRED)

if(AFTERGLOW_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()

# Debian's OpenImageIO config lists /usr/include/opencv4 among its include folders although
# OpenCV is only an optional plugin dependency; drop folders that do not exist rather than
# pulling in all of OpenCV.
foreach(_oiio_target OpenImageIO::OpenImageIO OpenImageIO::OpenImageIO_Util)
  if(TARGET ${_oiio_target})
    get_target_property(_dirs ${_oiio_target} INTERFACE_INCLUDE_DIRECTORIES)
    if(_dirs)
      set(_kept)
      foreach(_d IN LISTS _dirs)
        if(EXISTS "${_d}" OR _d MATCHES "^\\$<")
          list(APPEND _kept "${_d}")
        endif()
      endforeach()
      set_target_properties(${_oiio_target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_kept}")
    endif()
  endif()
endforeach()
