#include "relight/formats/positioned_file.h"

#include <fmt/format.h>

#include "core/error.h"

namespace photomat {

namespace fs = std::filesystem;

PositionedFileWriter::PositionedFileWriter(const fs::path& path, std::string_view header,
                                           std::size_t size)
    : file_(path), size_(size) {
  if (header.size() > size) throw Error(path, "the header is larger than the file");
  {
    std::ofstream create(file_.temp(), std::ios::binary | std::ios::trunc);
    create.write(header.data(), static_cast<std::streamsize>(header.size()));
    create.close();
    if (!create) throw Error(path, "cannot create the file");
  }
  // The full size up front (a sparse tail where the file system allows): every band is then
  // written at its offset, in any order.
  std::error_code ec;
  fs::resize_file(file_.temp(), size, ec);
  if (ec) throw Error(path, fmt::format("cannot make it {} bytes: {}", size, ec.message()));
  stream_.open(file_.temp(), std::ios::binary | std::ios::in | std::ios::out);
  if (!stream_) throw Error(path, "cannot open the file for writing");
}

void PositionedFileWriter::Write(std::size_t offset, std::span<const std::uint8_t> bytes) {
  if (offset > size_ || bytes.size() > size_ - offset) {
    throw Error(path(), fmt::format("bytes {}..{} are past the file's end ({})", offset,
                                    offset + bytes.size(), size_));
  }
  stream_.seekp(static_cast<std::streamoff>(offset));
  stream_.write(reinterpret_cast<const char*>(bytes.data()),
                static_cast<std::streamsize>(bytes.size()));
  if (!stream_) throw Error(path(), fmt::format("cannot write {} bytes", bytes.size()));
}

void PositionedFileWriter::Commit() {
  stream_.close();
  if (!stream_) throw Error(path(), "cannot write: closing the file failed");
  file_.Commit();
}

}  // namespace photomat
