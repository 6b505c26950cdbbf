#include "core/jpeg_structure.h"

#include <fmt/format.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr int kMarkerPrefix = 0xFF;
constexpr int kStartOfImage = 0xD8;
constexpr int kEndOfImage = 0xD9;
constexpr int kStartOfScan = 0xDA;

// Markers without a length field: TEM and the restart markers RST0..RST7.
bool IsStandalone(int marker) { return marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7); }

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};

// The file's bytes in order, read in 64 KiB blocks; -1 at its end.
class ByteReader {
 public:
  explicit ByteReader(std::FILE* file) : file_(file), buffer_(std::size_t{1} << 16) {}

  int Next() {
    if (position_ == filled_ && !Fill()) return -1;
    ++offset_;
    return static_cast<unsigned char>(buffer_[position_++]);
  }

  // Skips `count` bytes; false when the file ends first.
  bool Skip(std::size_t count) {
    while (count > 0) {
      if (position_ == filled_ && !Fill()) return false;
      const std::size_t step = std::min(count, filled_ - position_);
      position_ += step;
      offset_ += step;
      count -= step;
    }
    return true;
  }

  // Bytes read so far: where the file ended, once Next returned -1.
  std::uint64_t offset() const { return offset_; }

 private:
  bool Fill() {
    filled_ = std::fread(buffer_.data(), 1, buffer_.size(), file_);
    position_ = 0;
    return filled_ > 0;
  }

  std::FILE* file_;
  std::vector<char> buffer_;
  std::size_t position_ = 0;
  std::size_t filled_ = 0;
  std::uint64_t offset_ = 0;
};

// The marker code after one or more FF bytes, skipping any other bytes before them (libjpeg
// tolerates such "extraneous bytes" with a warning); -1 at the end of the file.
int NextMarker(ByteReader& bytes) {
  int byte = bytes.Next();
  while (byte >= 0 && byte != kMarkerPrefix) byte = bytes.Next();
  while (byte == kMarkerPrefix) byte = bytes.Next();
  return byte;
}

// A scan's compressed data up to the marker that ends it (FF 00 is a stuffed data byte, RSTn a
// restart inside the scan); returns that marker's code, or -1 at the end of the file.
int SkipCompressedData(ByteReader& bytes) {
  while (true) {
    int byte = bytes.Next();
    if (byte < 0) return -1;
    if (byte != kMarkerPrefix) continue;
    do {
      byte = bytes.Next();
    } while (byte == kMarkerPrefix);
    if (byte < 0) return -1;
    if (byte != 0x00 && !IsStandalone(byte)) return byte;
  }
}

std::string CutShort(std::uint64_t offset, const std::string& where) {
  return fmt::format("the file ends at byte {} {}, before the end-of-image marker: it is cut short",
                     offset, where);
}

std::optional<std::string> WalkMarkers(ByteReader& bytes) {
  if (bytes.Next() != kMarkerPrefix || bytes.Next() != kStartOfImage) {
    return "it does not start with the JPEG start-of-image marker";
  }
  int scans = 0;
  int marker = NextMarker(bytes);
  while (true) {
    if (marker < 0) return CutShort(bytes.offset(), "between two segments");
    if (marker == kEndOfImage) return std::nullopt;
    if (IsStandalone(marker)) {
      marker = NextMarker(bytes);
      continue;
    }
    const int high = bytes.Next(), low = bytes.Next();
    if (low < 0) return CutShort(bytes.offset(), fmt::format("in segment FF{:02X}", marker));
    const int length = (high << 8) | low;
    if (length < 2) return fmt::format("segment FF{:02X} has the length {}", marker, length);
    if (!bytes.Skip(static_cast<std::size_t>(length - 2))) {
      return CutShort(bytes.offset(), fmt::format("in segment FF{:02X}", marker));
    }
    if (marker != kStartOfScan) {
      marker = NextMarker(bytes);
      continue;
    }
    ++scans;
    marker = SkipCompressedData(bytes);
    if (marker < 0) {
      return CutShort(bytes.offset(), fmt::format("inside the compressed data of scan {}", scans));
    }
  }
}

}  // namespace

std::optional<std::string> FindJpegTruncation(const fs::path& path) {
  const std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(path, fmt::format("cannot open: {}", std::strerror(errno)));
  // The common case: the image's end-of-image marker is the file's last two bytes. (A file cut
  // inside its compressed data cannot end so: there FF is always followed by 00 or a restart.)
  std::array<unsigned char, 2> last{};
  if (std::fseek(file.get(), -2, SEEK_END) == 0 &&
      std::fread(last.data(), 1, last.size(), file.get()) == last.size() &&
      last[0] == kMarkerPrefix && last[1] == kEndOfImage) {
    return std::nullopt;
  }
  std::rewind(file.get());
  ByteReader bytes(file.get());
  return WalkMarkers(bytes);
}

void CheckJpegIsWhole(const fs::path& path) {
  if (const std::optional<std::string> fault = FindJpegTruncation(path)) {
    throw Error(path, "truncated JPEG: " + *fault);
  }
}

}  // namespace photomat
