#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace photomat {

// Bounds-checked reading of the binary interchange files (.ptm, .rti): a text header of short
// lines, then a binary payload. Every fault is an Error naming the file, and the line where there
// is one ("a.ptm: line 5: expected 6 scale values, got \"0.5 x\""). Nothing reads past the data.
class HeaderReader {
 public:
  // Lines longer than this are not header lines (a binary file, or garbage).
  static constexpr std::size_t kMaxLineLength = 1024;

  HeaderReader(std::span<const std::uint8_t> data, std::filesystem::path file);

  // The next line, without its "\n" and any trailing "\r", spaces or tabs (real headers carry a
  // space before the newline, .rti files CRLF). `what` names the expected content in errors.
  std::string_view Line(std::string_view what);
  // True if the next line starts with `prefix` (without consuming it).
  bool NextLineStartsWith(std::string_view prefix) const;

  // `count` whitespace-separated numbers, from as many lines as it takes (a PTM's width and
  // height may be on one line or two); a line holding more than the numbers still missing, or a
  // token that is not wholly a number, is an error.
  std::vector<long long> Integers(std::size_t count, std::string_view what);
  std::vector<double> Reals(std::size_t count, std::string_view what);

  // `count` little-endian IEEE float32 values; Error if fewer bytes remain.
  std::vector<float> BinaryFloats(std::size_t count, std::string_view what);
  // The next `count` bytes; Error naming `what` and the shortfall if fewer remain.
  std::span<const std::uint8_t> Bytes(std::size_t count, std::string_view what);

  std::size_t offset() const { return offset_; }
  std::size_t remaining() const { return data_.size() - offset_; }
  int line_number() const { return line_; }
  const std::filesystem::path& file() const { return file_; }

  [[noreturn]] void Fail(const std::string& fault) const;
  // The same, prefixed with the current line number.
  [[noreturn]] void FailAtLine(const std::string& fault) const;

 private:
  template <typename T>
  std::vector<T> Numbers(std::size_t count, std::string_view what);

  std::span<const std::uint8_t> data_;
  std::filesystem::path file_;
  std::size_t offset_ = 0;
  int line_ = 0;
};

}  // namespace photomat
