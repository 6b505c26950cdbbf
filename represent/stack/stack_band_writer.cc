#include "represent/stack/stack_band_writer.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// The placeholder of late detail `key`: a JSON string of exactly `bytes` bytes, quotes included,
// that no other part of a header holds.
std::string LatePlaceholder(const std::string& key, std::size_t bytes) {
  std::string text = "\"photomat:late-detail:" + key + ":";
  if (text.size() + 1 > bytes) throw Error(fmt::format("late detail name too long: {}", key));
  text.append(bytes - 1 - text.size(), '.');
  return text + "\"";
}

// Overwrites each placeholder in the header of the closed file `temp` with its value's JSON.
void PatchLateDetails(const fs::path& temp, const fs::path& path,
                      const std::vector<std::string>& keys, const nlohmann::json& values,
                      std::size_t description_bytes) {
  std::fstream file(temp, std::ios::in | std::ios::out | std::ios::binary);
  if (!file) throw Error(path, "cannot reopen the written stack to complete its description");
  // The header (attributes, then the offset table) comes first: the description plus a margin
  // for the other attributes.
  std::string head(description_bytes + (std::size_t{1} << 16), '\0');
  file.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(file.gcount()));
  file.clear();
  for (const std::string& key : keys) {
    const std::string placeholder = LatePlaceholder(key, StackBandWriter::kLateDetailBytes);
    const std::size_t at = head.find(placeholder);
    if (at == std::string::npos) {
      throw Error(path, fmt::format("the header has no place for \"{}\"", key));
    }
    std::string value = values.at(key).dump();
    value.resize(placeholder.size(), ' ');
    file.seekp(static_cast<std::streamoff>(at));
    file.write(value.data(), static_cast<std::streamsize>(value.size()));
  }
  file.close();
  if (!file) throw Error(path, "cannot complete the description of the written stack");
}

}  // namespace

StackBandWriter::StackBandWriter(const fs::path& path, const nlohmann::json& description,
                                 std::vector<std::string> channel_names, int width, int height,
                                 ExrCompression compression, std::vector<std::string> late_details)
    : writer_(path, width, height, std::move(channel_names),
              [&] {
                nlohmann::json with_places = description;
                for (const std::string& key : late_details) {
                  // The placeholder's text without its quotes: dump() adds them back.
                  const std::string placeholder = LatePlaceholder(key, kLateDetailBytes);
                  with_places["details"][key] = placeholder.substr(1, placeholder.size() - 2);
                }
                ImageWriteOptions options;
                options.exr_compression = compression;
                options.attributes[kStackAttribute] = with_places.dump();
                return options;
              }()),
      late_details_(std::move(late_details)),
      // At most: the keys' placeholders come with their names, quotes and separators.
      description_bytes_(description.dump().size() + late_details_.size() * 2 * kLateDetailBytes) {}

void StackBandWriter::Commit(const nlohmann::json& late_values) {
  for (const std::string& key : late_details_) {
    if (!late_values.contains(key)) {
      throw Error(writer_.path(), fmt::format("no value for the late detail \"{}\"", key));
    }
    if (late_values.at(key).dump().size() > kLateDetailBytes) {
      throw Error(writer_.path(),
                  fmt::format("\"{}\" is longer than its {} bytes", key, kLateDetailBytes));
    }
  }
  if (late_details_.empty()) {
    writer_.Commit();
    return;
  }
  writer_.Commit([&](const fs::path& temp) {
    PatchLateDetails(temp, writer_.path(), late_details_, late_values, description_bytes_);
  });
}

}  // namespace photomat
