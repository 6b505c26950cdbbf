#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string_view>

#include "core/atomic_file.h"

namespace photomat {

// A file of known size written at positions (README, "Streamed relighting and export"): the .ptm
// and .rti formats hold their rows bottom to top, so a writer fed bands of rows top to bottom
// puts each band at its final offset instead of holding the whole payload. The file is created
// under a temporary name with its header and its full size (the rest zero until written), and
// Commit() renames it into place; destroyed without Commit(), it is removed.
class PositionedFileWriter {
 public:
  // Throws Error naming `path` when the file cannot be created at `size` bytes (>= the header).
  PositionedFileWriter(const std::filesystem::path& path, std::string_view header,
                       std::size_t size);
  const std::filesystem::path& path() const { return file_.path(); }
  std::size_t size() const { return size_; }
  // Writes `bytes` at `offset`; throws Error naming the file when they run past its size or the
  // write fails (a full disk).
  void Write(std::size_t offset, std::span<const std::uint8_t> bytes);
  // Flushes and renames the file into place; throws Error naming it on failure.
  void Commit();

 private:
  PendingFile file_;
  std::fstream stream_;
  std::size_t size_;
};

}  // namespace photomat
