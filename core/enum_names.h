#pragma once

#include <fmt/format.h>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "core/error.h"

namespace photomat {

// The names of an enumeration's values on the command line and in files: one table per
// enumeration, read both ways, so that a name is written in one place.
template <typename Enum>
struct NamedValue {
  Enum value;
  std::string_view name;
};

// The name of `value` in `names` ("?" for a value the table does not hold).
template <typename Enum, std::size_t N>
constexpr std::string_view NameOf(Enum value, const std::array<NamedValue<Enum>, N>& names) {
  for (const NamedValue<Enum>& entry : names) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

// The value named `name`, or nullopt.
template <typename Enum, std::size_t N>
constexpr std::optional<Enum> FindValueNamed(std::string_view name,
                                             const std::array<NamedValue<Enum>, N>& names) {
  for (const NamedValue<Enum>& entry : names) {
    if (entry.name == name) return entry.value;
  }
  return std::nullopt;
}

// The value named `name`; throws Error "unknown <what> 'name' (a, b or c)" for any other name.
template <typename Enum, std::size_t N>
Enum ValueNamed(std::string_view name, const std::array<NamedValue<Enum>, N>& names,
                std::string_view what) {
  std::string choices;
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i].name == name) return names[i].value;
    choices += i == 0 ? "" : i + 1 == N ? " or " : ", ";
    choices += names[i].name;
  }
  throw Error(fmt::format("unknown {} '{}' ({})", what, name, choices));
}

}  // namespace photomat
