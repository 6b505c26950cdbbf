#include "relight/render/output_folder.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// True when `folder` may be replaced: an empty folder, or one whose marker file names `format`.
bool IsReplaceable(const fs::path& folder, std::string_view marker, std::string_view format) {
  std::error_code ec;
  if (fs::is_empty(folder, ec) && !ec) return true;
  const fs::path marker_path = folder / marker;
  if (!fs::is_regular_file(marker_path, ec)) return false;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadTextFile(marker_path));
    return json.is_object() && json.value("format", std::string()) == format;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

void WriteFolderAtomically(const fs::path& folder, std::string_view marker, std::string_view format,
                           const std::function<void(const fs::path& temp)>& write) {
  if (folder.empty()) throw Error("no output folder given");
  const fs::path target = folder.filename().empty() ? folder.parent_path() : folder;
  std::error_code ec;
  if (fs::exists(target, ec)) {
    if (!fs::is_directory(target, ec)) throw Error(target, "exists and is not a folder");
    if (!IsReplaceable(target, marker, format)) {
      throw Error(target, fmt::format("exists and is not a {} folder (no {} saying so); remove "
                                      "it or choose another folder",
                                      format, marker));
    }
  }
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  fs::create_directories(parent, ec);
  if (ec) throw Error(parent, fmt::format("cannot create folder: {}", ec.message()));
  const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
  const fs::path temp =
      parent / fmt::format(".{}.tmp-{}-{:x}", target.filename().string(), getpid(), stamp);
  const auto discard = [&] { fs::remove_all(temp, ec); };
  try {
    if (!fs::create_directory(temp, ec) || ec) {
      throw Error(temp, fmt::format("cannot create folder: {}", ec.message()));
    }
    write(temp);
    if (fs::exists(target, ec)) {
      // A previous output of the same kind: moved aside first so the rename cannot fail on a
      // non-empty folder, and removed only once the new one is in place.
      const fs::path old =
          parent / fmt::format(".{}.old-{}-{:x}", target.filename().string(), getpid(), stamp);
      fs::rename(target, old, ec);
      if (ec) throw Error(target, fmt::format("cannot replace: {}", ec.message()));
      fs::rename(temp, target, ec);
      if (ec) {
        std::error_code restore;
        fs::rename(old, target, restore);
        throw Error(target, fmt::format("cannot write: {}", ec.message()));
      }
      fs::remove_all(old, ec);
    } else {
      fs::rename(temp, target, ec);
      if (ec) throw Error(target, fmt::format("cannot write: {}", ec.message()));
    }
  } catch (const Error&) {
    discard();
    throw;
  } catch (const std::exception& error) {
    discard();
    throw Error(target, fmt::format("cannot write: {}", error.what()));
  }
}

}  // namespace photomat
