#pragma once

#include <filesystem>
#include <string>

namespace photomat {

// A hidden folder for intermediate files that no one else should see or keep (the scratch map
// stacks a streamed export of photographs is made from), created beside the outputs so that it
// is on their disk, and removed with everything in it when the ScratchFolder is destroyed, however
// the work ended: a failed or interrupted run leaves nothing behind. Its name is unique per
// process, thread and instant. Move-only.
class ScratchFolder {
 public:
  // Creates `.NAME.scratch-...` in `parent` (which must exist); throws Error naming `parent` when
  // the folder cannot be made.
  ScratchFolder(const std::filesystem::path& parent, const std::string& name);
  ~ScratchFolder();
  ScratchFolder(ScratchFolder&& other) noexcept;
  ScratchFolder& operator=(ScratchFolder&&) = delete;
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace photomat
