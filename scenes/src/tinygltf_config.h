// The one way afterglow includes tinygltf. The implementation (tinygltf_impl.cpp) is compiled
// with these macros, and TinyGLTF's class layout and default members depend on them, so every
// file that uses tinygltf must include this header instead of <tiny_gltf.h>.
//
// Images are never decoded by tinygltf: textures go through OpenImageIO (texture_io.cpp), and
// external image files are opened by the importer itself, so tinygltf only keeps their URI.
#pragma once

#ifndef TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE
#endif
#ifndef TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#endif
#ifndef TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#endif

// Debian's tiny_gltf.h includes <nlohmann/json.hpp> itself (TINYGLTF_NO_INCLUDE_JSON unset).
#include <tiny_gltf.h>
