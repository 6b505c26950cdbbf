// `photomat capture` and `photomat devices`: live capture from a camera while a light controller
// switches the lights of a plan (README, "Capture").
#include "apps/capture_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <sstream>

#include "apps/cli_main.h"
#include "capture/live/capture_session.h"
#include "capture/live/libcamera_frame_source.h"
#include "capture/live/light_controller.h"
#include "capture/live/light_plan.h"
#include "capture/live/open_frame_source.h"
#include "capture/live/v4l2_frame_source.h"
#include "core/error.h"
#include "core/progress.h"

namespace photomat::app {
namespace {

// "YUYV", "YUYV:640x480" or "640x480" (size only: the device's default pixel format).
FrameFormat ParseFormat(const std::string& text) {
  FrameFormat format;
  std::string code = text, size;
  if (const auto colon = text.find(':'); colon != std::string::npos) {
    code = text.substr(0, colon);
    size = text.substr(colon + 1);
  }
  const auto pixel_format = ParsePixelFormat(code);
  if (!pixel_format) {
    throw Error(
        fmt::format("--format \"{}\": unknown pixel format \"{}\" (photomat decodes {}, "
                    "and FLOAT for folder sources)",
                    text, code, SupportedPixelFormatList()));
  }
  format.pixel_format = *pixel_format;
  if (!size.empty()) {
    char x = 0;
    std::istringstream in(size);
    if (!(in >> format.width >> x >> format.height) || x != 'x' || format.width <= 0 ||
        format.height <= 0) {
      throw Error(fmt::format("--format \"{}\": expected FOURCC or FOURCC:WIDTHxHEIGHT", text));
    }
  }
  return format;
}

std::vector<double> ParseBracket(const std::string& text) {
  std::vector<double> factors;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      factors.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error(fmt::format("--bracket \"{}\": expected factors like 0.25,1,4", text));
    }
  }
  return factors;
}

std::string FormatDevice(const DeviceDescription& device) {
  std::string text = fmt::format("  {}  {}\n", device.id, device.description);
  if (!device.error.empty()) return text + fmt::format("    error: {}\n", device.error);
  for (const OfferedFormat& format : device.formats) {
    std::string sizes;
    for (const auto& [w, h] : format.sizes) sizes += fmt::format(" {}x{}", w, h);
    text += fmt::format("    {:<6} {:<28}{}{}\n", format.code, format.description,
                        sizes.empty() ? " (sizes not listed)" : sizes,
                        format.pixel_format ? "" : "  [not decoded by photomat]");
  }
  for (const CameraControl& control : device.controls) {
    text += fmt::format("    control {:<32} [{} .. {}] default {}{}\n", control.name,
                        control.minimum, control.maximum, control.default_value,
                        control.current ? fmt::format(" now {}", *control.current) : "");
  }
  return text;
}

struct CaptureCommandOptions {
  std::string device;
  std::string lights;
  std::string controller;
  std::filesystem::path out;
  std::string format;
  std::string bracket;
  std::string encoding = "srgb";
  std::string image_format = "exr";
  int frames = 1;
  int settle_ms = 200;
  int frame_timeout_ms = 5000;
  int controller_timeout_ms = 10000;
  int controller_retries = 2;
  std::optional<double> exposure_us;
  std::optional<double> gain;
  bool no_dark = false;
  bool raw = false;
  bool resume = false;
};

void AddCaptureOptions(CLI::App& command, CaptureCommandOptions& options) {
  command
      .add_option("--device", options.device,
                  "Camera: /dev/videoN (V4L2), libcamera:ID or libcamera:INDEX, or "
                  "folder:PATH (replay a set on disk, for dry runs)")
      ->required();
  command.add_option("--lights", options.lights,
                     "Light plan: thesis (12 tilts x slants 30, 45, 60), a dome's .lp file or "
                     "other light file, or a list SLANT,TILT;SLANT,TILT;... (optional with "
                     "--resume)");
  command
      .add_option("--controller", options.controller,
                  "Light controller: manual, command:TEMPLATE (placeholders {n} {count} "
                  "{state} {slant} {tilt} {x} {y} {z}) or serial:PORT[,BAUD]")
      ->required();
  command.add_option("--out", options.out, "Output folder")->required();
  command.add_option("--format", options.format,
                     "Pixel format and size: GREY, Y16, YUYV, MJPG, RGB3, BGR3 (FLOAT for "
                     "folders), optionally :WIDTHxHEIGHT (default: the best the camera offers)");
  command.add_option("--frames", options.frames, "Frames averaged per light")
      ->capture_default_str();
  command
      .add_option("--settle-ms", options.settle_ms,
                  "Wait after each light switch or exposure change; earlier frames are "
                  "dropped")
      ->capture_default_str();
  command.add_option("--frame-timeout-ms", options.frame_timeout_ms, "Longest wait for one frame")
      ->capture_default_str();
  command.add_option("--exposure-us", options.exposure_us, "Exposure time in microseconds");
  command.add_option("--gain", options.gain, "Gain (the camera's units)");
  command.add_option("--bracket", options.bracket,
                     "Exposure bracketing: factors of --exposure-us (e.g. 0.25,1,4), merged to "
                     "one linear HDR image per light");
  command.add_flag("--no-dark", options.no_dark,
                   "Skip the dark frame (all lights off) taken at the start and subtracted");
  command
      .add_option("--encoding", options.encoding,
                  "How 8-bit camera samples encode light: srgb (video cameras) or linear "
                  "(machine-vision cameras with gamma off); Y16 is always linear")
      ->capture_default_str();
  command
      .add_option("--image-format", options.image_format,
                  "Images written: exr (float, keeps HDR and sub-code precision) or png16")
      ->capture_default_str();
  command.add_flag("--raw", options.raw, "libcamera: configure the raw sensor stream");
  command
      .add_option("--controller-timeout-ms", options.controller_timeout_ms,
                  "Time for the light controller to confirm a switch")
      ->capture_default_str();
  command
      .add_option("--controller-retries", options.controller_retries,
                  "Further attempts when the light controller does not confirm")
      ->capture_default_str();
  command.add_flag("--resume", options.resume,
                   "Continue the interrupted session in --out with its recorded plan and "
                   "settings (a different camera format is refused)");
}

// A new session's settings (a resumed one keeps its recorded settings).
CaptureSettings SettingsOf(const CaptureCommandOptions& options,
                           const std::optional<FrameFormat>& format) {
  CaptureSettings settings;
  settings.format = format;
  settings.frames_per_light = options.frames;
  settings.settle = std::chrono::milliseconds(options.settle_ms);
  settings.frame_timeout = std::chrono::milliseconds(options.frame_timeout_ms);
  settings.controls = {options.exposure_us, options.gain};
  if (!options.bracket.empty()) settings.bracket = ParseBracket(options.bracket);
  settings.dark_frame = !options.no_dark;
  settings.image_format =
      options.image_format == "exr" ? CaptureImageFormat::kExr : CaptureImageFormat::kPng16;
  return settings;
}

void WarnAboutCaptureSummary(const CaptureSummary& summary) {
  if (summary.clipped_pixels > 0) {
    spdlog::warn(
        "{} pixels were clipped (at full scale at every exposure): lower the exposure "
        "or use --bracket",
        summary.clipped_pixels);
  }
  if (summary.exposure_mismatches > 0) {
    spdlog::info(
        "{} frames were dropped: the camera reported another exposure than the one requested "
        "(it applies exposure changes late)",
        summary.exposure_mismatches);
  }
}

void RunCapture(const CaptureCommandOptions& options) {
  const auto encoding = ParseColourSpace(options.encoding);
  if (!encoding) throw Error("--encoding: expected srgb or linear");
  if (options.image_format != "exr" && options.image_format != "png16") {
    throw Error("--image-format: expected exr or png16");
  }
  if (!options.resume && options.lights.empty()) {
    throw Error("--lights is required (except with --resume)");
  }
  std::optional<FrameFormat> format;
  if (!options.format.empty()) format = ParseFormat(options.format);
  std::optional<LightPlan> plan;
  if (!options.lights.empty()) plan = ReadLightPlan(options.lights);

  std::unique_ptr<LightController> controller = MakeLightController(
      options.controller, std::chrono::milliseconds(options.controller_timeout_ms),
      options.controller_retries);
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.device, {*encoding, options.raw});
  // The manual controller prompts on the terminal; a progress bar would overwrite it.
  TerminalProgressBar bar(stderr);
  Progress* progress = options.controller == "manual" ? nullptr : &bar;

  CaptureSummary summary;
  if (options.resume) {
    summary = ResumeCaptureSession(*source, *controller, options.out, format, plan, progress);
  } else {
    summary = RunCaptureSession(*source, *controller, options.out, *plan,
                                SettingsOf(options, format), progress);
  }
  WarnAboutCaptureSummary(summary);
  fmt::print("captured {} of {} lights ({} already on disk) in {} from {} to {}\n",
             summary.lights_before + summary.lights_taken, summary.lights_total,
             summary.lights_before, ToString(summary.format), source->name(), options.out.string());
}

}  // namespace

void AddCaptureCommand(CLI::App& app) {
  BindCommand(*AddListedCommand(app, "capture"), AddCaptureOptions, RunCapture);
}

void AddDevicesCommand(CLI::App& app) {
  CLI::App* command = AddListedCommand(app, "devices");
  command->callback([] {
    LinuxV4l2Syscalls syscalls;
    const std::vector<DeviceDescription> v4l2 = ListV4l2Devices(syscalls);
    fmt::print("V4L2 (--device /dev/videoN):\n");
    if (v4l2.empty()) fmt::print("  no video capture device under /dev\n");
    for (const DeviceDescription& device : v4l2) fmt::print("{}", FormatDevice(device));
    fmt::print("libcamera {} (--device libcamera:ID):\n", LibcameraVersion());
    try {
      const std::vector<DeviceDescription> cameras = ListLibcameraCameras();
      if (cameras.empty()) fmt::print("  no camera\n");
      for (const DeviceDescription& camera : cameras) fmt::print("{}", FormatDevice(camera));
    } catch (const Error& error) {
      fmt::print("  error: {}\n", error.what());
    }
    fmt::print("Replay (--device folder:PATH): any photometric set on disk\n");
  });
}

}  // namespace photomat::app
