#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

namespace photomat {

// A clear error before a long command starts when the disk cannot hold its outputs (README,
// "Streamed relighting and export"): every command that writes large files (fit, relight,
// export) estimates what it will write and checks the free space of the output's file system
// first, instead of failing hours later on a full disk.

// Bytes an image file of these dimensions holds at most: the uncompressed samples plus
// kImageFileOverhead. IMPLEMENTER CHOICE: compressed formats (PNG's deflate, EXR's rle) can make
// a file of noise slightly larger than its samples (deflate's stored blocks add 5 bytes per 64
// KiB; rle one byte per 128), so the estimate adds 1 % to the samples and a fixed 64 KiB for
// headers and metadata. The estimate is an upper bound for every format photomat writes; for
// smooth maps the files are smaller.
std::size_t ImageFileBytes(int width, int height, int channels, int bytes_per_sample);
inline constexpr std::size_t kImageFileOverhead = std::size_t{64} << 10;

// The bytes an unprivileged process may still write to the file system holding `path`
// (statvfs: f_bavail x f_frsize). `path` need not exist yet: its nearest existing ancestor is
// asked. Throws Error naming the path when the file system cannot be queried.
std::size_t AvailableDiskBytes(const std::filesystem::path& path);

// Throws Error "DIR: not enough disk space for WHAT: N MB needed here, M MB free" when
// `needed_bytes` exceed the space available in `folder`'s file system: `available_bytes` when given
// (tests), else AvailableDiskBytes(folder).
void CheckDiskSpace(const std::filesystem::path& folder, std::size_t needed_bytes,
                    const std::string& what,
                    std::optional<std::size_t> available_bytes = std::nullopt);

}  // namespace photomat
