#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace photomat {

// Whether a JPEG file holds its whole compressed image. OpenImageIO's JPEG reader, like most,
// decodes a file cut short without an error: libjpeg only warns ("premature end of data") and
// fills the missing rows with grey, which a fit would take as photographs. photomat therefore
// checks the file's structure when it opens it.
//
// Returns std::nullopt for a complete stream: the end-of-image marker (FF D9) closes the primary
// image. A file that ends with that marker passes at the cost of reading its last two bytes;
// another is walked marker by marker from its start (segments by their lengths, each scan's
// compressed data up to the next marker), so that data a camera appends after the image (a
// motion photo's video) is allowed. Otherwise returns the fault, e.g. "the file ends at byte
// 5000 inside the compressed data of scan 1, before the end-of-image marker: it is cut short".
// Throws Error when the file cannot be read.
std::optional<std::string> FindJpegTruncation(const std::filesystem::path& path);

// Throws Error "PATH: truncated JPEG: FAULT" when FindJpegTruncation finds a fault.
void CheckJpegIsWhole(const std::filesystem::path& path);

}  // namespace photomat
