#include "core/atomic_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <future>
#include <sstream>
#include <system_error>
#include <thread>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

fs::path TemporarySibling(const fs::path& path) {
  // Unique per process, thread and instant; collisions would need two writers of the same file
  // in the same nanosecond.
  const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
  const auto thread = std::hash<std::thread::id>{}(std::this_thread::get_id());
  return path.parent_path() / fmt::format(".{}.tmp-{}-{:x}-{:x}{}", path.stem().string(), getpid(),
                                          thread & 0xffffff, stamp, path.extension().string());
}

// fsync a file or folder; returns errno or 0.
int SyncPath(const fs::path& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
  if (fd < 0) return errno;
  const int result = ::fsync(fd) == 0 ? 0 : errno;
  ::close(fd);
  return result;
}

// fdatasync of `path`; returns its errno or 0. A file that cannot be opened (not created yet, or
// no descriptor free) returns 0: this flush is an early start, and Commit's own flush of the file
// decides.
int DataSyncIfPresent(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return 0;
  const int result = ::fdatasync(fd) == 0 ? 0 : errno;
  ::close(fd);
  return result;
}

}  // namespace

PendingFile::PendingFile(fs::path path) : path_(std::move(path)) {
  const fs::path parent = path_.parent_path().empty() ? fs::path(".") : path_.parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw Error(path_, fmt::format("cannot write: folder {} does not exist", parent.string()));
  }
  temp_ = TemporarySibling(path_);
}

PendingFile::PendingFile(PendingFile&& other) noexcept
    : path_(std::move(other.path_)),
      temp_(std::move(other.temp_)),
      pending_(other.pending_),
      writeback_(std::move(other.writeback_)),
      writeback_error_(other.writeback_error_) {
  other.pending_ = false;
}

PendingFile::~PendingFile() {
  FinishWriteback();  // the flush's thread must not outlive the temporary's name
  if (!pending_) return;
  std::error_code ec;
  fs::remove(temp_, ec);
}

void PendingFile::StartWriteback() {
  if (writeback_.valid()) {
    if (writeback_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    FinishWriteback();
  }
  try {
    writeback_ = std::async(std::launch::async, DataSyncIfPresent, temp_);
  } catch (const std::system_error&) {
    // No thread to be had (an address-space limit, say): Commit's flush does it all.
  }
}

void PendingFile::FinishWriteback() {
  if (!writeback_.valid()) return;
  const int error = writeback_.get();
  if (writeback_error_ == 0) writeback_error_ = error;
}

void PendingFile::Commit() {
  std::error_code ec;
  FinishWriteback();
  if (int err = writeback_error_ != 0 ? writeback_error_ : SyncPath(temp_, false); err != 0) {
    fs::remove(temp_, ec);
    pending_ = false;
    throw Error(path_, fmt::format("cannot write: {}", std::strerror(err)));
  }
  fs::rename(temp_, path_, ec);
  pending_ = false;
  if (ec) {
    std::error_code ignored;
    fs::remove(temp_, ignored);
    throw Error(path_, fmt::format("cannot write: {}", ec.message()));
  }
  // Best effort: the rename is done; a failed folder sync loses nothing.
  SyncPath(path_.parent_path().empty() ? fs::path(".") : path_.parent_path(), true);
}

void WriteFileAtomically(const fs::path& path,
                         const std::function<void(const fs::path& temp)>& write) {
  PendingFile file(path);
  try {
    write(file.temp());
    file.Commit();
  } catch (const Error& error) {
    throw error.InFile(path);
  } catch (const std::exception& error) {
    throw Error(path, fmt::format("cannot write: {}", error.what()));
  }
}

void WriteSerializedAtomically(const fs::path& path,
                               const std::function<std::string()>& serialize) {
  std::string bytes;
  try {
    bytes = serialize();
  } catch (const Error& error) {
    throw error.InFile(path);
  }
  WriteTextFileAtomically(path, bytes);
}

void WriteTextFileAtomically(const fs::path& path, std::string_view contents) {
  WriteFileAtomically(path, [&](const fs::path& temp) {
    std::ofstream out(temp, std::ios::binary);
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) throw Error(path, fmt::format("cannot write: {}", std::strerror(errno)));
  });
}

std::string ReadTextFile(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path, "file not found");
  if (fs::is_directory(path, ec)) throw Error(path, "is a folder, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, fmt::format("cannot open: {}", std::strerror(errno)));
  std::ostringstream contents;
  contents << in.rdbuf();
  if (in.bad()) throw Error(path, "read error");
  return contents.str();
}

}  // namespace photomat
