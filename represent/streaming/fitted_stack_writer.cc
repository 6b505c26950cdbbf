#include "represent/streaming/fitted_stack_writer.h"

#include <fmt/format.h>

#include "core/error.h"

namespace photomat {

namespace fs = std::filesystem;

FittedStackWriter::FittedStackWriter(fs::path path, int width, int height,
                                     ExrCompression compression, StackProvenance provenance)
    : path_(std::move(path)),
      width_(width),
      height_(height),
      compression_(compression),
      provenance_(std::move(provenance)) {}

void FittedStackWriter::Write(int first_row, const Representation& band) {
  const int rows = band.maps().height();
  if (first_row < next_row_ || first_row + rows > height_) {
    throw Error(path_, fmt::format("a band of rows {} to {} after row {} of {}", first_row,
                                   first_row + rows, next_row_, height_));
  }
  const nlohmann::json& details = band.details();
  if (!writer_) {
    const nlohmann::json description = StackDescription(band, provenance_);
    std::vector<std::string> late;
    for (const char* summary : {"robust_summary", "pbr_summary"}) {
      if (const nlohmann::json& described = description["details"];
          described.is_object() && described.contains(summary)) {
        late.emplace_back(summary);
      }
    }
    names_ = band.maps().channel_names();
    writer_.emplace(path_, description, names_, width_, height_, compression_, std::move(late));
  }
  if (details.is_object()) {
    if (const auto robust = details.find("robust_summary"); robust != details.end()) {
      if (!robust_summary_) robust_summary_.emplace();
      robust_summary_->Add(RobustFitSummary::FromJson(*robust));
    }
    if (const auto pbr = details.find("pbr_summary"); pbr != details.end()) {
      if (!pbr_summary_) pbr_summary_.emplace();
      pbr_summary_->Add(PbrFitSummary::FromJson(*pbr));
    }
  }
  WriteZeros(first_row - next_row_);
  writer_->Write(band.maps());
  next_row_ = first_row + rows;
}

void FittedStackWriter::Commit() {
  if (!writer_) throw Error(path_, "no band of the set was fitted");
  WriteZeros(height_ - next_row_);
  nlohmann::json late = nlohmann::json::object();
  if (robust_summary_) late["robust_summary"] = robust_summary_->ToJson();
  if (pbr_summary_) late["pbr_summary"] = pbr_summary_->ToJson();
  writer_->Commit(late);
}

void FittedStackWriter::WriteZeros(int rows) {
  if (rows > 0) writer_->Write(Image(width_, rows, maps()));
}

}  // namespace photomat
