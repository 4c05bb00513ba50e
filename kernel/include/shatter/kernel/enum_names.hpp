#pragma once
// Reading an enum back from its name: the one lookup behind every `*_named`
// function of the libraries, so a parser accepts exactly the names the library
// prints with its own `*_name` function.

#include <initializer_list>
#include <optional>
#include <string_view>

namespace shatter {

/// The value among `values` whose name by `name_of` is `name`; nullopt when none
/// is (names are compared exactly, case included). Never throws.
template <class Enum>
std::optional<Enum> enum_named(std::string_view name, std::initializer_list<Enum> values,
                               std::string_view (*name_of)(Enum)) {
  for (Enum value : values) {
    if (name_of(value) == name) return value;
  }
  return std::nullopt;
}

}  // namespace shatter
