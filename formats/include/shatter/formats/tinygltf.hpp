#pragma once
// tinygltf as formats compiles it: its implementation is built once, in
// src/export.cpp (which defines TINYGLTF_IMPLEMENTATION before including this),
// without image support, since shatter's GLBs hold no textures. Code that reads
// or writes glTF with tinygltf includes this header, never <tiny_gltf.h> itself,
// and links shatter::formats: the class's default members depend on these
// macros, and tinygltf's own warnings stay out of shatter's -Wall builds.

#ifndef TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE
#endif
#ifndef TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#endif
#ifndef TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#endif
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#ifndef __clang__  // a g++ warning clang does not know
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <tiny_gltf.h>
#pragma GCC diagnostic pop
