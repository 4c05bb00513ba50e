#pragma once
// Reading back the GLBs shatter writes, for tests: decode the bytes with
// tinygltf and copy an accessor's elements out. Header-only, and without a test
// framework like the rest of support/: failures throw std::runtime_error, which
// Catch reports with the message. Link shatter::meshtree, which compiles
// tinygltf (shatter/formats/tinygltf.hpp).

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "shatter/formats/tinygltf.hpp"

namespace shatter::test {

/// The model in GLB `bytes`; throws naming tinygltf's error or warning when it
/// does not load cleanly.
inline tinygltf::Model decode_glb(const std::string& bytes) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string error, warning;
  const bool loaded = loader.LoadBinaryFromMemory(&model, &error, &warning,
                                                  reinterpret_cast<const unsigned char*>(bytes.data()),
                                                  static_cast<unsigned int>(bytes.size()));
  if (!loaded || !error.empty() || !warning.empty()) {
    throw std::runtime_error("tinygltf error: " + error + " warning: " + warning);
  }
  return model;
}

/// The elements of accessor `accessor_index`, `components` values of T (float
/// or uint32) each, copied out of its tightly packed buffer view. Throws when
/// the view is strided or the accessor reaches past its view or buffer.
template <class T>
std::vector<T> accessor_values(const tinygltf::Model& model, int accessor_index, std::size_t components) {
  const tinygltf::Accessor& accessor = model.accessors.at(static_cast<std::size_t>(accessor_index));
  const tinygltf::BufferView& view = model.bufferViews.at(static_cast<std::size_t>(accessor.bufferView));
  const tinygltf::Buffer& buffer = model.buffers.at(static_cast<std::size_t>(view.buffer));
  const std::size_t count = accessor.count * components;
  if (view.byteStride != 0) throw std::runtime_error("accessor " + std::to_string(accessor_index) + " is strided");
  if (view.byteOffset + accessor.byteOffset + count * sizeof(T) > buffer.data.size() ||
      count * sizeof(T) > view.byteLength) {
    throw std::runtime_error("accessor " + std::to_string(accessor_index) + " reaches past its data");
  }
  std::vector<T> values(count);
  std::memcpy(values.data(), buffer.data.data() + view.byteOffset + accessor.byteOffset, count * sizeof(T));
  return values;
}

}  // namespace shatter::test
