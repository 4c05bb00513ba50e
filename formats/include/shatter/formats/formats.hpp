#pragma once
// The whole public API of shatter::formats, one include, with everything it
// stores (shatter/meshtree/meshtree.hpp): the library's API from a closed mesh to
// a stored, exported mesh tree. Each header holds:
//
//   file
//     file.hpp          the .shatter format, byte by byte: encode_shatter, decode_shatter, read and write
//   export
//     export.hpp        mesh files per node selection, and the whole tree as one GLB
//
// Not included: tinygltf.hpp, tinygltf as formats compiles it, only for code that
// reads or writes glTF with tinygltf itself (it sets tinygltf's macros).

#include "shatter/meshtree/meshtree.hpp"

#include "shatter/formats/export.hpp"
#include "shatter/formats/file.hpp"
