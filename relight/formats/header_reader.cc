#include "relight/formats/header_reader.h"

#include <fmt/format.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>

#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {

HeaderReader::HeaderReader(std::span<const std::uint8_t> data, std::filesystem::path file)
    : data_(data), file_(std::move(file)) {}

void HeaderReader::Fail(const std::string& fault) const { throw Error(file_, fault); }

void HeaderReader::FailAtLine(const std::string& fault) const {
  throw Error(file_, fmt::format("line {}: {}", line_, fault));
}

std::string_view HeaderReader::Line(std::string_view what) {
  if (offset_ >= data_.size()) {
    Fail(fmt::format("truncated: the file ends where {} was expected (line {})", what, line_ + 1));
  }
  const auto* begin = reinterpret_cast<const char*>(data_.data()) + offset_;
  const std::size_t available = data_.size() - offset_;
  const std::size_t limit = std::min(available, kMaxLineLength + 1);
  const void* newline = std::memchr(begin, '\n', limit);
  ++line_;
  if (newline == nullptr) {
    if (available > kMaxLineLength) {
      FailAtLine(fmt::format("expected {}, found no line end in {} bytes", what, kMaxLineLength));
    }
    FailAtLine(fmt::format("truncated: {} has no line end", what));
  }
  const auto length = static_cast<std::size_t>(static_cast<const char*>(newline) - begin);
  offset_ += length + 1;
  std::string_view line(begin, length);
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) {
    line.remove_suffix(1);
  }
  return line;
}

bool HeaderReader::NextLineStartsWith(std::string_view prefix) const {
  if (remaining() < prefix.size()) return false;
  return std::memcmp(data_.data() + offset_, prefix.data(), prefix.size()) == 0;
}

template <typename T>
std::vector<T> HeaderReader::Numbers(std::size_t count, std::string_view what) {
  std::vector<T> values;
  while (values.size() < count) {
    const std::string_view line = Line(what);
    const auto tokens = SplitWhitespace(line);
    if (tokens.empty() || tokens.size() > count - values.size()) {
      FailAtLine(fmt::format("expected {} ({} number{}), got \"{}\"", what, count,
                             count == 1 ? "" : "s", line.substr(0, 80)));
    }
    for (const std::string_view token : tokens) {
      T value{};
      const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
      if (ec != std::errc() || end != token.data() + token.size()) {
        FailAtLine(fmt::format("expected {}: \"{}\" is not a{} number", what, token.substr(0, 40),
                               std::is_integral_v<T> ? "n integer" : ""));
      }
      if constexpr (std::is_floating_point_v<T>) {
        if (!std::isfinite(value)) FailAtLine(fmt::format("{}: {} is not finite", what, token));
      }
      values.push_back(value);
    }
  }
  return values;
}

std::vector<long long> HeaderReader::Integers(std::size_t count, std::string_view what) {
  return Numbers<long long>(count, what);
}

std::vector<double> HeaderReader::Reals(std::size_t count, std::string_view what) {
  return Numbers<double>(count, what);
}

std::span<const std::uint8_t> HeaderReader::Bytes(std::size_t count, std::string_view what) {
  if (count > remaining()) {
    Fail(fmt::format("truncated: {} bytes of {} expected, {} remain", count, what, remaining()));
  }
  const auto bytes = data_.subspan(offset_, count);
  offset_ += count;
  return bytes;
}

std::vector<float> HeaderReader::BinaryFloats(std::size_t count, std::string_view what) {
  static_assert(std::endian::native == std::endian::little, "float payloads are little-endian");
  const auto bytes = Bytes(count * sizeof(float), what);
  std::vector<float> values(count);
  std::memcpy(values.data(), bytes.data(), bytes.size());
  for (float v : values) {
    if (!std::isfinite(v)) Fail(fmt::format("{}: {} is not finite", what, v));
  }
  return values;
}

}  // namespace photomat
