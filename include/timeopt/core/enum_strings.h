#pragma once

// FromString beside every ToString: each enum's ToString (found by argument-dependent lookup) is
// the one table of its names, and these templates read it backwards, so a name is never spelt
// twice. Each module declares `bool FromString(const std::string&, Enum*)` next to its ToString and
// defines it with EnumFromString over the list of its values.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace timeopt {

// Sets *value to the enumerator whose ToString is `text` and returns true; false (and *value
// untouched) when no enumerator has that name.
template <typename Enum, std::size_t N>
bool EnumFromString(const std::string& text, const std::array<Enum, N>& all, Enum* value) {
  for (const Enum candidate : all) {
    if (text == ToString(candidate)) {
      *value = candidate;
      return true;
    }
  }
  return false;
}

// The names of `all`, in order (e.g. for a command line's list of allowed values).
template <typename Enum, std::size_t N>
std::vector<std::string> EnumNames(const std::array<Enum, N>& all) {
  std::vector<std::string> names;
  for (const Enum value : all) names.emplace_back(ToString(value));
  return names;
}

// "a, b or c": the names of `all`, for messages and command-line help.
template <typename Enum, std::size_t N>
std::string EnumChoices(const std::array<Enum, N>& all) {
  std::string text;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) text += i + 1 == N ? " or " : ", ";
    text += ToString(all[i]);
  }
  return text;
}

}  // namespace timeopt
