#include "core/scratch_folder.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <system_error>
#include <thread>

#include "core/error.h"

namespace photomat {

namespace fs = std::filesystem;

ScratchFolder::ScratchFolder(const fs::path& parent, const std::string& name) {
  const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
  const auto thread = std::hash<std::thread::id>{}(std::this_thread::get_id());
  const fs::path folder = parent.empty() ? fs::path(".") : parent;
  path_ =
      folder / fmt::format(".{}.scratch-{}-{:x}-{:x}", name, getpid(), thread & 0xffffff, stamp);
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw Error(folder, "cannot hold a scratch folder: the folder does not exist");
  }
  if (!fs::create_directory(path_, ec)) {
    throw Error(folder,
                fmt::format("cannot create the scratch folder {}: {}", path_.filename().string(),
                            ec ? ec.message() : "it exists already"));
  }
}

ScratchFolder::~ScratchFolder() {
  if (path_.empty()) return;
  std::error_code ec;  // best effort: a destructor cannot report
  fs::remove_all(path_, ec);
}

ScratchFolder::ScratchFolder(ScratchFolder&& other) noexcept : path_(std::move(other.path_)) {
  other.path_.clear();
}

}  // namespace photomat
