#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace photomat {

// The one error type of photomat. It names the file at fault (when there is one) and says what is
// wrong with it, so that a command-line user sees a single actionable line:
//   "captures/lights.lp: line 7: zero-length light vector".
class Error : public std::runtime_error {
 public:
  explicit Error(std::string fault);
  Error(std::filesystem::path file, std::string fault);

  const std::filesystem::path& file() const noexcept { return file_; }
  const std::string& fault() const noexcept { return fault_; }

  // The same fault, attributed to `file` (used when a lower layer did not know the file name).
  Error InFile(const std::filesystem::path& file) const;

 private:
  std::filesystem::path file_;
  std::string fault_;
};

}  // namespace photomat
