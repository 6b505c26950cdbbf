#include "core/disk_space.h"

#include <fmt/format.h>
#include <sys/statvfs.h>

#include <cerrno>
#include <cstring>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// Megabytes, rounded up (so that "needs 1 MB" is never printed for 1.5 MB).
std::size_t MegabytesUp(std::size_t bytes) { return (bytes + (std::size_t{1} << 20) - 1) >> 20; }

// `path` or its nearest ancestor that exists (an output folder is often made later).
fs::path ExistingAncestor(const fs::path& path) {
  fs::path existing = fs::absolute(path);
  std::error_code ec;
  while (!fs::exists(existing, ec) && existing.has_parent_path() &&
         existing.parent_path() != existing) {
    existing = existing.parent_path();
  }
  return existing;
}

}  // namespace

std::size_t ImageFileBytes(int width, int height, int channels, int bytes_per_sample) {
  const std::size_t samples = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                              static_cast<std::size_t>(channels) *
                              static_cast<std::size_t>(bytes_per_sample);
  return samples + samples / 100 + kImageFileOverhead;
}

std::size_t AvailableDiskBytes(const fs::path& path) {
  const fs::path existing = ExistingAncestor(path);
  struct statvfs info {};
  if (statvfs(existing.c_str(), &info) != 0) {
    throw Error(path, fmt::format("cannot query the free disk space of {}: {}", existing.string(),
                                  std::strerror(errno)));
  }
  return static_cast<std::size_t>(info.f_bavail) * static_cast<std::size_t>(info.f_frsize);
}

void CheckDiskSpace(const fs::path& folder, std::size_t needed_bytes, const std::string& what,
                    std::optional<std::size_t> available_bytes) {
  const std::size_t available = available_bytes ? *available_bytes : AvailableDiskBytes(folder);
  if (needed_bytes <= available) return;
  throw Error(folder, fmt::format("not enough disk space for {}: {} MB needed here, {} MB free",
                                  what, MegabytesUp(needed_bytes), available >> 20));
}

}  // namespace photomat
