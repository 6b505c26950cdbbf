#include "core/atomic_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
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

}  // namespace

void WriteFileAtomically(const fs::path& path,
                         const std::function<void(const fs::path& temp)>& write) {
  const fs::path parent = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw Error(path, fmt::format("cannot write: folder {} does not exist", parent.string()));
  }
  const fs::path temp = TemporarySibling(path);
  try {
    write(temp);
    if (int err = SyncPath(temp, false); err != 0) {
      throw Error(path, fmt::format("cannot write: {}", std::strerror(err)));
    }
    fs::rename(temp, path, ec);
    if (ec) throw Error(path, fmt::format("cannot write: {}", ec.message()));
  } catch (const Error& error) {
    fs::remove(temp, ec);
    throw error.InFile(path);
  } catch (const std::exception& error) {
    fs::remove(temp, ec);
    throw Error(path, fmt::format("cannot write: {}", error.what()));
  }
  SyncPath(parent, true);  // Best effort: the rename is done; a failed folder sync loses nothing.
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
