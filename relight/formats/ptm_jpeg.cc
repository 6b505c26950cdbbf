#include "relight/formats/ptm_jpeg.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void Fail(const fs::path& file, const std::string& fault) {
  if (file.empty()) throw Error(fault);
  throw Error(file, fault);
}

// One greyscale JPEG stream, decoded through OpenImageIO from memory.
PlaneBytes DecodeJpeg(std::span<const std::uint8_t> stream, int width, int height, int plane,
                      const fs::path& file) {
  const auto fail = [&](const std::string& why) {
    Fail(file, fmt::format("JPEG plane {}: {}", plane, why));
  };
  if (stream.empty()) fail("empty stream");
  // OpenImageIO reads from memory through an IOProxy handed to the JPEG reader it creates.
  OIIO::Filesystem::IOMemReader memory(stream.data(), stream.size());
  auto input = OIIO::ImageInput::create("plane.jpg", false, nullptr, &memory);
  OIIO::ImageSpec spec;
  if (!input || !input->set_ioproxy(&memory) || !input->open("plane.jpg", spec)) {
    const std::string why = input ? input->geterror() : OIIO::geterror();
    fail(fmt::format("not a readable JPEG ({})", why));
  }
  if (spec.width != width || spec.height != height || spec.nchannels != 1) {
    fail(fmt::format("{}x{} with {} channel(s), expected {}x{} greyscale", spec.width, spec.height,
                     spec.nchannels, width, height));
  }
  // Row by row: read_image allocates a large staging buffer per call, which dominates the time
  // of small planes.
  PlaneBytes pixels(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y) {
    if (!input->read_scanline(y, 0, OIIO::TypeDesc::UINT8,
                              pixels.data() + static_cast<std::size_t>(y) * width)) {
      fail(fmt::format("cannot decode: {}", input->geterror()));
    }
  }
  return pixels;
}

std::string EncodeJpeg(const PlaneBytes& plane, int width, int height, int quality) {
  std::vector<unsigned char> buffer;
  OIIO::Filesystem::IOVecOutput memory(buffer);
  auto output = OIIO::ImageOutput::create("plane.jpg");
  OIIO::ImageSpec spec(width, height, 1, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", fmt::format("jpeg:{}", quality));
  if (!output || !output->set_ioproxy(&memory) || !output->open("plane.jpg", spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, plane.data()) || !output->close()) {
    throw Error(fmt::format("cannot encode a JPEG plane: {}",
                            output ? output->geterror() : OIIO::geterror()));
  }
  return std::string(buffer.begin(), buffer.end());
}

// (residual - 128 + prediction) mod 256: the byte arithmetic every decoder uses.
void AddPrediction(PlaneBytes& residual, const PlaneBytes& prediction) {
  for (std::size_t p = 0; p < residual.size(); ++p) {
    residual[p] = static_cast<std::uint8_t>(residual[p] - 128 + prediction[p]);
  }
}

void ApplySideInformation(std::span<const std::uint8_t> records, PlaneBytes& plane, int index,
                          const fs::path& file) {
  for (std::size_t k = 0; k + 5 <= records.size(); k += 5) {
    const std::size_t pixel = (std::size_t{records[k]} << 24) |
                              (std::size_t{records[k + 1]} << 16) |
                              (std::size_t{records[k + 2]} << 8) | records[k + 3];
    if (pixel >= plane.size()) {
      Fail(file, fmt::format("JPEG plane {}: side information names pixel {} of {}", index, pixel,
                             plane.size()));
    }
    plane[pixel] = records[k + 4];
  }
}

// The planes in decoding order (the coding's order is a checked permutation).
std::vector<int> DecodingSequence(const PtmJpegCoding& coding) {
  std::vector<int> sequence(coding.planes.size());
  for (std::size_t s = 0; s < coding.planes.size(); ++s) {
    sequence[coding.planes[s].order] = static_cast<int>(s);
  }
  return sequence;
}

}  // namespace

PtmJpegCoding PtmJpegCoding::Unpredicted(int plane_count, int quality) {
  PtmJpegCoding coding;
  coding.quality = quality;
  coding.planes.resize(plane_count);
  for (int s = 0; s < plane_count; ++s) coding.planes[s].order = s;
  return coding;
}

void CheckPtmJpegCoding(const PtmJpegCoding& coding, int plane_count, int width, int height,
                        const fs::path& file) {
  const int n = plane_count;
  if (static_cast<int>(coding.planes.size()) != n) {
    Fail(file, fmt::format("the JPEG coding describes {} planes, the format has {}",
                           coding.planes.size(), n));
  }
  std::vector<int> decoded_at(n, -1);
  for (int s = 0; s < n; ++s) {
    const PtmPlaneCoding& plane = coding.planes[s];
    if (plane.order < 0 || plane.order >= n || decoded_at[plane.order] != -1) {
      Fail(file, fmt::format("the JPEG plane decoding order is not a permutation of the {} planes "
                             "(plane {} has order {})",
                             n, s, plane.order));
    }
    decoded_at[plane.order] = s;
    if (plane.reference < -1 || plane.reference >= n || plane.reference == s) {
      Fail(file, fmt::format("JPEG plane {}: invalid reference plane {}", s, plane.reference));
    }
    if (plane.motion_compensated &&
        (std::abs(plane.motion_x) >= width || std::abs(plane.motion_y) >= height)) {
      Fail(file,
           fmt::format("JPEG plane {}: motion vector ({}, {}) is not shorter than the {} x {} "
                       "image",
                       s, plane.motion_x, plane.motion_y, width, height));
    }
  }
  // A cycle is also an order fault, but naming it tells what is wrong with the file.
  for (int s = 0; s < n; ++s) {
    std::string chain = std::to_string(s);
    int at = s;
    for (int step = 0; step < n && coding.planes[at].reference >= 0; ++step) {
      at = coding.planes[at].reference;
      chain += fmt::format(" -> {}", at);
      if (at == s) Fail(file, fmt::format("the JPEG reference planes form a cycle: {}", chain));
    }
  }
  for (int s = 0; s < n; ++s) {
    const int r = coding.planes[s].reference;
    if (r >= 0 && coding.planes[r].order > coding.planes[s].order) {
      Fail(file, fmt::format("JPEG plane {} refers to plane {}, which is decoded after it", s, r));
    }
  }
}

PlaneBytes PredictPtmPlane(const PlaneBytes& reference, const PtmPlaneCoding& plane, int width,
                           int height) {
  const int dx = plane.motion_compensated ? plane.motion_x : 0;
  const int dy = plane.motion_compensated ? plane.motion_y : 0;
  PlaneBytes prediction(reference.size());
  for (int y = 0; y < height; ++y) {
    const int ry = std::clamp(y + dy, 0, height - 1);
    for (int x = 0; x < width; ++x) {
      const int rx = std::clamp(x + dx, 0, width - 1);
      const std::uint8_t v = reference[static_cast<std::size_t>(ry) * width + rx];
      prediction[static_cast<std::size_t>(y) * width + x] =
          plane.inverted ? static_cast<std::uint8_t>(255 - v) : v;
    }
  }
  return prediction;
}

std::vector<PlaneBytes> DecodePtmJpegPlanes(const PtmJpegCoding& coding,
                                            std::span<const PtmJpegStream> streams, int width,
                                            int height, const fs::path& file) {
  std::vector<PlaneBytes> planes(coding.planes.size());
  for (int s : DecodingSequence(coding)) {
    PlaneBytes plane = DecodeJpeg(streams[s].jpeg, width, height, s, file);
    if (const int r = coding.planes[s].reference; r >= 0) {
      AddPrediction(plane, PredictPtmPlane(planes[r], coding.planes[s], width, height));
    }
    ApplySideInformation(streams[s].side_information, plane, s, file);
    planes[s] = std::move(plane);
  }
  return planes;
}

std::vector<EncodedPtmPlane> EncodePtmJpegPlanes(const PtmJpegCoding& coding,
                                                 const std::vector<PlaneBytes>& planes, int width,
                                                 int height) {
  CheckPtmJpegCoding(coding, static_cast<int>(planes.size()), width, height, {});
  for (const PlaneBytes& plane : planes) {
    if (plane.size() != static_cast<std::size_t>(width) * height) {
      throw Error(
          fmt::format("a PTM plane of {} bytes is not {} x {}", plane.size(), width, height));
    }
  }
  if (coding.quality < 1 || coding.quality > 100) {
    throw Error(fmt::format("JPEG quality {} is not in 1..100", coding.quality));
  }
  std::vector<EncodedPtmPlane> encoded(planes.size());
  std::vector<PlaneBytes> decoded(planes.size());  // what the decoder will reconstruct
  for (int s : DecodingSequence(coding)) {
    const PlaneBytes& truth = planes[s];
    const int r = coding.planes[s].reference;
    PlaneBytes prediction;
    PlaneBytes residual = truth;
    if (r >= 0) {
      prediction = PredictPtmPlane(decoded[r], coding.planes[s], width, height);
      for (std::size_t p = 0; p < residual.size(); ++p) {
        residual[p] = static_cast<std::uint8_t>(truth[p] + 128 - prediction[p]);
      }
    }
    encoded[s].jpeg = EncodeJpeg(residual, width, height, coding.quality);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(encoded[s].jpeg.data());
    PlaneBytes plane = DecodeJpeg({bytes, encoded[s].jpeg.size()}, width, height, s, {});
    if (r >= 0) AddPrediction(plane, prediction);
    for (std::size_t p = 0; p < plane.size(); ++p) {
      if (std::abs(plane[p] - truth[p]) <= coding.side_information_tolerance) continue;
      for (int shift : {24, 16, 8, 0}) {
        encoded[s].side_information.push_back(static_cast<char>((p >> shift) & 0xff));
      }
      encoded[s].side_information.push_back(static_cast<char>(truth[p]));
      plane[p] = truth[p];
    }
    decoded[s] = std::move(plane);
  }
  return encoded;
}

}  // namespace photomat
