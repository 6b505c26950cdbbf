#include "capture/live/capture_session.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "capture/io/capture_manifest.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

// ---- session file ----

json ToJson(const CaptureSettings& s) {
  json bracket = json::array();
  for (double f : s.bracket) bracket.push_back(f);
  json out = {{"frames_per_light", s.frames_per_light},
              {"settle_ms", s.settle.count()},
              {"frame_timeout_ms", s.frame_timeout.count()},
              {"bracket", bracket},
              {"dark_frame", s.dark_frame},
              {"image_format", s.image_format == CaptureImageFormat::kExr ? "exr" : "png16"},
              {"clip_level", s.clip_level}};
  out["exposure_us"] = s.controls.exposure_us ? json(*s.controls.exposure_us) : json(nullptr);
  out["gain"] = s.controls.gain ? json(*s.controls.gain) : json(nullptr);
  return out;
}

std::optional<double> OptionalNumber(const JsonReader& reader, const std::string& key) {
  if (!reader.Has(key) || reader.value().at(key).is_null()) return std::nullopt;
  return reader[key].Number();
}

CaptureSettings SettingsFromJson(const JsonReader& r) {
  CaptureSettings s;
  s.frames_per_light = r["frames_per_light"].Integer();
  s.settle = std::chrono::milliseconds(r["settle_ms"].Integer());
  s.frame_timeout = std::chrono::milliseconds(r["frame_timeout_ms"].Integer());
  s.bracket = r["bracket"].Numbers();
  s.dark_frame = r["dark_frame"].Boolean();
  const std::string format = r["image_format"].String();
  if (format != "exr" && format != "png16") r["image_format"].Fail("expected \"exr\" or \"png16\"");
  s.image_format = format == "exr" ? CaptureImageFormat::kExr : CaptureImageFormat::kPng16;
  s.clip_level = r["clip_level"].Number();
  s.controls.exposure_us = OptionalNumber(r, "exposure_us");
  s.controls.gain = OptionalNumber(r, "gain");
  return s;
}

// ---- frames ----

void Accumulate(Image& sum, const Image& frame, const std::string& device) {
  if (sum.empty()) {
    sum = Image(frame.width(), frame.height(), frame.channels());
  } else if (!sum.SameShape(frame)) {
    throw Error(device, fmt::format("frame of {}x{}x{} in a stream of {}x{}x{}", frame.width(),
                                    frame.height(), frame.channels(), sum.width(), sum.height(),
                                    sum.channels()));
  }
  auto out = sum.values();
  auto in = frame.values();
  for (std::size_t i = 0; i < out.size(); ++i) out[i] += in[i];
}

// K frames averaged, all exposed at or after `ready` (and at the requested exposure where the
// camera reports one).
struct Exposure {
  Image mean;
  Image clipped;  // 1 where any frame reached the clip level, per sample
  std::vector<std::uint64_t> sequences;
  std::size_t mismatches = 0;  // frames dropped for a reported exposure that was not requested
};

// One bracket step of one light (or of the dark frame): what the frames must have.
struct Step {
  Clock::time_point changed;          // the light switch or exposure change
  std::optional<double> exposure_us;  // requested; unset: the device's own
  std::string what;                   // "light 3 of 36, exposure 1 of 2" for messages
};

class Session {
 public:
  Session(FrameSource& source, LightController& controller, fs::path out, CaptureSessionState state)
      : source_(source), controller_(controller), out_(std::move(out)), state_(std::move(state)) {}

  CaptureSummary Run(Progress* progress) {
    CaptureSummary summary;
    summary.lights_total = static_cast<int>(state_.plan.lights.size());
    summary.lights_before = static_cast<int>(state_.captured.size());
    summary.format = state_.format;
    source_.Start();
    LoadOrTakeDarkFrames();
    NullProgress no_progress;
    Progress& report = OrNull(progress, no_progress);
    report.Start(summary.lights_before > 0
                     ? fmt::format("capture (resumed at {}/{})", summary.lights_before + 1,
                                   summary.lights_total)
                     : std::string("capture"),
                 summary.lights_total - summary.lights_before);
    for (int index = summary.lights_before; index < summary.lights_total; ++index) {
      const CapturedLight& taken = TakeLight(index);
      summary.clipped_pixels += taken.clipped_pixels;
      summary.exposure_mismatches += taken.exposure_mismatches;
      ++summary.lights_taken;
      report.Advance();
    }
    report.Finish();
    Switch({0, summary.lights_total, std::nullopt});  // leave the lights off
    source_.Stop();
    return summary;
  }

 private:
  std::vector<double> Factors() const {
    return state_.settings.bracket.empty() ? std::vector<double>{1.0} : state_.settings.bracket;
  }

  Clock::time_point Switch(const LightState& light) {
    controller_.SwitchTo(light);
    source_.LightChanged(light);
    return Clock::now();
  }

  // Sets the exposure of bracket `b` when bracketing; returns the step, changed at the later of
  // `switched` and the exposure change.
  Step SetBracket(std::size_t b, Clock::time_point switched, std::string what) {
    const CaptureSettings& s = state_.settings;
    Step step{switched, s.controls.exposure_us, std::move(what)};
    if (s.bracket.empty()) return step;
    step.exposure_us = *s.controls.exposure_us * s.bracket[b];
    step.what += fmt::format(", exposure {} of {}", b + 1, s.bracket.size());
    source_.SetExposure(*step.exposure_us);
    step.changed = std::max(switched, Clock::now());
    return step;
  }

  // Whether `frame` has the step's exposure; counts one that has not and refuses it past the
  // limit.
  bool HasStepExposure(const Frame& frame, const Step& step, Exposure& exposure) const {
    if (!step.exposure_us || !frame.metadata.exposure_us ||
        ExposureMatches(*step.exposure_us, *frame.metadata.exposure_us)) {
      return true;
    }
    if (++exposure.mismatches >= kMaxExposureMismatchFrames) {
      throw Error(source_.name(),
                  fmt::format("{}: the camera did not reach the requested exposure of {} us "
                              "in {} frames (the last reported {} us; tolerance {} % or {} us)",
                              step.what, *step.exposure_us, kMaxExposureMismatchFrames,
                              *frame.metadata.exposure_us, kExposureMatchRelative * 100,
                              kExposureMatchAbsoluteUs));
    }
    return false;
  }

  Exposure Grab(const Step& step) {
    const CaptureSettings& s = state_.settings;
    const Clock::time_point ready = step.changed + s.settle;
    std::this_thread::sleep_until(ready);
    // Stale frames (queued before the change) are dropped; the whole grab is bounded.
    const Clock::time_point deadline = ready + s.frame_timeout * (s.frames_per_light + 1);
    Exposure exposure;
    Image sum;
    while (static_cast<int>(exposure.sequences.size()) < s.frames_per_light) {
      Frame frame = source_.Grab(s.frame_timeout);
      if (frame.metadata.timestamp < ready) {
        if (Clock::now() > deadline) {
          throw Error(
              source_.name(),
              fmt::format("frame time-out: no frame exposed after the "
                          "{} ms settle time came within {} ms",
                          s.settle.count(), (s.frame_timeout * (s.frames_per_light + 1)).count()));
        }
        continue;
      }
      if (!HasStepExposure(frame, step, exposure)) continue;
      if (exposure.clipped.empty()) {
        exposure.clipped = Image(frame.image.width(), frame.image.height(), frame.image.channels());
      }
      Accumulate(sum, frame.image, source_.name());
      auto values = frame.image.values();
      auto clipped = exposure.clipped.values();
      for (std::size_t i = 0; i < values.size(); ++i) {
        if (values[i] >= s.clip_level) clipped[i] = 1.0f;
      }
      exposure.sequences.push_back(frame.metadata.sequence);
    }
    for (float& v : sum.values()) v /= static_cast<float>(s.frames_per_light);
    exposure.mean = std::move(sum);
    return exposure;
  }

  ImageWriteOptions WriteOptions() const {
    ImageWriteOptions options;
    options.sample_type = state_.settings.image_format == CaptureImageFormat::kExr
                              ? SampleType::kFloat
                              : SampleType::kUint16;
    return options;
  }

  std::string Extension() const {
    return state_.settings.image_format == CaptureImageFormat::kExr ? "exr" : "png";
  }

  void LoadOrTakeDarkFrames() {
    const std::vector<double> factors = Factors();
    if (!state_.settings.dark_frame) return;
    if (state_.dark_files.size() == factors.size()) {
      for (const std::string& file : state_.dark_files) {
        darks_.push_back(ReadImage(out_ / file).image);
        if (!darks_.back().SameShape(darks_.front())) {
          throw Error(out_ / file, "dark frame of another size than the first");
        }
      }
      return;
    }
    const Clock::time_point off = Switch({0, static_cast<int>(state_.plan.lights.size()), {}});
    state_.dark_files.clear();
    for (std::size_t b = 0; b < factors.size(); ++b) {
      Exposure dark = Grab(SetBracket(b, off, "the dark frame"));
      const std::string file =
          factors.size() == 1 ? std::string("dark.exr") : fmt::format("dark_{}.exr", b);
      ImageWriteOptions options;
      options.sample_type = SampleType::kFloat;  // the dark level is small: keep every bit
      WriteImage(out_ / file, dark.mean, options);
      darks_.push_back(std::move(dark.mean));
      state_.dark_files.push_back(file);
    }
    WriteCaptureSession(out_ / kCaptureSessionName, state_);
  }

  // Dark-subtracted, bracket-merged image of one light; counts clipped pixels.
  Image Merge(const std::vector<Exposure>& exposures, const std::vector<double>& factors,
              std::size_t& clipped_pixels) const {
    const Image& first = exposures.front().mean;
    Image merged(first.width(), first.height(), first.channels());
    for (std::size_t b = 0; b < exposures.size(); ++b) {
      if (!darks_.empty() && !darks_[b].SameShape(exposures[b].mean)) {
        throw Error(source_.name(), "frames differ in size from the dark frame");
      }
    }
    // Shortest exposure first: the fallback when a sample is clipped at every exposure.
    const std::size_t shortest = static_cast<std::size_t>(
        std::min_element(factors.begin(), factors.end()) - factors.begin());
    std::vector<char> pixel_clipped(first.pixel_count(), 0);
    auto out = merged.values();
    for (std::size_t i = 0; i < out.size(); ++i) {
      // Estimate in base-exposure units: sum of (mean - dark) over unclipped exposures divided by
      // the sum of their factors, which weights each exposure by its factor (longer exposures
      // carry more signal per unit of noise).
      double signal = 0.0, weight = 0.0;
      for (std::size_t b = 0; b < exposures.size(); ++b) {
        if (exposures[b].clipped.values()[i] != 0.0f) continue;
        const double dark = darks_.empty() ? 0.0 : darks_[b].values()[i];
        signal += exposures[b].mean.values()[i] - dark;
        weight += factors[b];
      }
      if (weight == 0.0) {
        const double dark = darks_.empty() ? 0.0 : darks_[shortest].values()[i];
        signal = exposures[shortest].mean.values()[i] - dark;
        weight = factors[shortest];
        pixel_clipped[i % first.pixel_count()] = 1;  // values are planar
      }
      out[i] = static_cast<float>(signal / weight);
    }
    clipped_pixels =
        static_cast<std::size_t>(std::count(pixel_clipped.begin(), pixel_clipped.end(), 1));
    return merged;
  }

  const CapturedLight& TakeLight(int index) {
    const int count = static_cast<int>(state_.plan.lights.size());
    const LightState light{index + 1, count, state_.plan.lights[index]};
    const Clock::time_point switched = Switch(light);
    const std::vector<double> factors = Factors();
    std::vector<Exposure> exposures;
    for (std::size_t b = 0; b < factors.size(); ++b) {
      exposures.push_back(
          Grab(SetBracket(b, switched, fmt::format("light {} of {}", index + 1, count))));
    }
    CapturedLight taken;
    taken.number = index + 1;
    taken.file = fmt::format("img_{:03}.{}", index, Extension());
    for (const Exposure& e : exposures) {
      taken.frames.insert(taken.frames.end(), e.sequences.begin(), e.sequences.end());
      taken.exposure_mismatches += e.mismatches;
    }
    const Image image = Merge(exposures, factors, taken.clipped_pixels);
    // Image first, then the state that lists it, then the manifest: whatever is listed exists.
    WriteImage(out_ / taken.file, image, WriteOptions());
    state_.captured.push_back(std::move(taken));
    WriteCaptureSession(out_ / kCaptureSessionName, state_);
    WriteManifest();
    return state_.captured.back();
  }

  void WriteManifest() const {
    CaptureManifest manifest;
    manifest.colour_space = ColourSpace::kLinear;
    for (const CapturedLight& taken : state_.captured) {
      manifest.images.push_back({taken.file, state_.plan.lights[taken.number - 1], {}, {}});
    }
    json bracket = json::array();
    for (double f : state_.settings.bracket) bracket.push_back(f);
    manifest.provenance = {{"capture",
                            {{"device", state_.device},
                             {"camera_format", ToString(state_.format)},
                             {"frames_per_light", state_.settings.frames_per_light},
                             {"bracket", bracket},
                             {"dark_frames", state_.dark_files},
                             {"plan", state_.plan.source},
                             {"lights_planned", state_.plan.lights.size()},
                             {"session", kCaptureSessionName}}}};
    WriteCaptureManifest(out_ / kCaptureManifestName, manifest);
  }

  FrameSource& source_;
  LightController& controller_;
  fs::path out_;
  CaptureSessionState state_;
  std::vector<Image> darks_;
};

void CheckSettings(const CaptureSettings& s) {
  if (s.frames_per_light < 1) throw Error("frames per light must be at least 1");
  if (s.settle.count() < 0) throw Error("the settle time cannot be negative");
  if (s.frame_timeout.count() <= 0) throw Error("the frame time-out must be positive");
  if (!s.bracket.empty() && !s.controls.exposure_us) {
    throw Error("exposure bracketing needs a base exposure (--exposure-us)");
  }
  for (double f : s.bracket) {
    if (!(f > 0.0)) throw Error(fmt::format("bracket factor {} must be positive", f));
  }
  if (!(s.clip_level > 0.0 && s.clip_level <= 1.0)) {
    throw Error("the clip level must be in (0, 1]");
  }
}

}  // namespace

bool ExposureMatches(double requested_us, double reported_us) {
  return std::abs(reported_us - requested_us) <=
         std::max(kExposureMatchRelative * requested_us, kExposureMatchAbsoluteUs);
}

void WriteCaptureSession(const fs::path& path, const CaptureSessionState& state) {
  json lights = json::array();
  for (const LightDirection& l : state.plan.lights) lights.push_back({l.x(), l.y(), l.z()});
  json captured = json::array();
  for (const CapturedLight& c : state.captured) {
    captured.push_back({{"light", c.number},
                        {"file", c.file},
                        {"frames", c.frames},
                        {"clipped_pixels", c.clipped_pixels},
                        {"exposure_mismatches", c.exposure_mismatches}});
  }
  const json document = {
      {"format", kCaptureSessionFormat},
      {"version", 1},
      {"device", state.device},
      {"camera_format",
       {{"pixel_format", ToString(state.format.pixel_format)},
        {"width", state.format.width},
        {"height", state.format.height}}},
      {"plan", {{"source", state.plan.source}, {"lights", lights}}},
      {"settings", ToJson(state.settings)},
      {"dark_frames", state.dark_files},
      {"captured", captured},
  };
  WriteJsonFile(path, document);
}

CaptureSessionState ReadCaptureSession(const fs::path& path) {
  const json document = ReadJsonFile(path);
  const JsonReader root(document, path);
  if (!document.is_object() || !root.Has("format") ||
      root["format"].String() != kCaptureSessionFormat) {
    root.Fail(fmt::format("not a photomat capture session (\"format\" must be \"{}\")",
                          kCaptureSessionFormat));
  }
  if (root["version"].Integer() != 1) root["version"].Fail("unsupported version");
  CaptureSessionState state;
  state.device = root["device"].String();
  const JsonReader format = root["camera_format"];
  const auto pixel_format = ParsePixelFormat(format["pixel_format"].String());
  if (!pixel_format) format["pixel_format"].Fail("unknown pixel format");
  state.format = {*pixel_format, format["width"].Integer(), format["height"].Integer()};
  const JsonReader plan = root["plan"];
  state.plan.source = plan["source"].String();
  for (std::size_t i = 0; i < plan["lights"].ArraySize(); ++i) {
    const std::vector<double> v = plan["lights"][i].Numbers();
    if (v.size() != 3) plan["lights"][i].Fail("expected [x, y, z]");
    state.plan.lights.push_back(LightDirection::FromVector(v[0], v[1], v[2]));
  }
  if (state.plan.lights.empty()) plan["lights"].Fail("no light in the plan");
  state.settings = SettingsFromJson(root["settings"]);
  for (std::size_t i = 0; i < root["dark_frames"].ArraySize(); ++i) {
    state.dark_files.push_back(root["dark_frames"][i].String());
  }
  const JsonReader captured = root["captured"];
  for (std::size_t i = 0; i < captured.ArraySize(); ++i) {
    const JsonReader entry = captured[i];
    CapturedLight c;
    c.number = entry["light"].Integer();
    if (c.number != static_cast<int>(i) + 1) {
      entry["light"].Fail(fmt::format("expected light {} (lights are taken in plan order)", i + 1));
    }
    c.file = entry["file"].String();
    for (double f : entry["frames"].Numbers()) c.frames.push_back(static_cast<std::uint64_t>(f));
    c.clipped_pixels = static_cast<std::size_t>(entry["clipped_pixels"].Number());
    // Sessions written before the exposure check have no count.
    if (entry.Has("exposure_mismatches")) {
      c.exposure_mismatches = static_cast<std::size_t>(entry["exposure_mismatches"].Number());
    }
    state.captured.push_back(std::move(c));
  }
  if (state.captured.size() > state.plan.lights.size()) {
    captured.Fail("more images than lights in the plan");
  }
  return state;
}

CaptureSummary RunCaptureSession(FrameSource& source, LightController& controller,
                                 const fs::path& out, const LightPlan& plan,
                                 const CaptureSettings& settings, Progress* progress) {
  CheckSettings(settings);
  if (plan.lights.empty()) throw Error("the light plan has no light");
  std::error_code ec;
  if (fs::exists(out / kCaptureSessionName, ec)) {
    const CaptureSessionState existing = ReadCaptureSession(out / kCaptureSessionName);
    throw Error(out, fmt::format("holds a capture session ({} of {} lights taken): resume it "
                                 "(--resume) or choose another folder",
                                 existing.captured.size(), existing.plan.lights.size()));
  }
  if (fs::exists(out / kCaptureManifestName, ec)) {
    throw Error(out, "already holds a photometric set (manifest.json): choose another folder");
  }
  fs::create_directories(out, ec);
  if (ec) throw Error(out, fmt::format("cannot create folder: {}", ec.message()));
  CaptureSessionState state;
  state.device = source.name();
  state.format = source.SetFormat(settings.format ? *settings.format : source.DefaultFormat());
  state.plan = plan;
  state.settings = settings;
  source.SetManualControls(settings.controls);
  WriteCaptureSession(out / kCaptureSessionName, state);
  return Session(source, controller, out, std::move(state)).Run(progress);
}

CaptureSummary ResumeCaptureSession(FrameSource& source, LightController& controller,
                                    const fs::path& out,
                                    const std::optional<FrameFormat>& requested_format,
                                    const std::optional<LightPlan>& plan, Progress* progress) {
  std::error_code ec;
  if (!fs::exists(out / kCaptureSessionName, ec)) {
    throw Error(out,
                fmt::format("no capture session to resume ({} is missing)", kCaptureSessionName));
  }
  CaptureSessionState state = ReadCaptureSession(out / kCaptureSessionName);
  CheckSettings(state.settings);
  if (plan && !SameLights(plan->lights, state.plan.lights)) {
    throw Error(out, fmt::format("the light plan differs from the session's ({} lights from {}): "
                                 "a resumed session keeps its plan",
                                 state.plan.lights.size(), state.plan.source));
  }
  const auto refuse = [&](const FrameFormat& other, const char* how) {
    return Error(out, fmt::format("camera format changed: the session was captured in {}, {} {}; "
                                  "refusing to mix formats in one set",
                                  ToString(state.format), how, ToString(other)));
  };
  if (requested_format && *requested_format != state.format) {
    throw refuse(*requested_format, "resuming asked for");
  }
  FrameFormat actual;
  try {
    actual = source.SetFormat(state.format);
  } catch (const Error& error) {
    throw Error(out, fmt::format("camera format changed: the session was captured in {} and {} "
                                 "cannot deliver it ({})",
                                 ToString(state.format), source.name(), error.fault()));
  }
  if (actual != state.format) throw refuse(actual, "the camera now delivers");
  source.SetManualControls(state.settings.controls);
  state.device = source.name();
  return Session(source, controller, out, std::move(state)).Run(progress);
}

}  // namespace photomat
