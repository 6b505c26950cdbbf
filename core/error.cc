#include "core/error.h"

namespace photomat {
namespace {

std::string Describe(const std::filesystem::path& file, const std::string& fault) {
  return file.empty() ? fault : file.string() + ": " + fault;
}

}  // namespace

Error::Error(std::string fault) : std::runtime_error(fault), fault_(std::move(fault)) {}

Error::Error(std::filesystem::path file, std::string fault)
    : std::runtime_error(Describe(file, fault)), file_(std::move(file)), fault_(std::move(fault)) {}

Error Error::InFile(const std::filesystem::path& file) const {
  return file_.empty() ? Error(file, fault_) : *this;
}

}  // namespace photomat
