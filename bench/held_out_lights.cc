// Relighting lights that were not captured (issue 19): fits each method on a capture without
// every K-th light and relights the held-out lights. Prints, per method, the mean PSNR over the
// held-out images, Dong's eta, the planes and the fit time. PSNR is over the mask's pixels and
// every channel, after the capture's light intensities are divided out, with the peak the
// largest value of the capture (both images clamped to [0, peak]): the images scaled to [0, 1].
//
//   held_out_lights SET [--every K] [--methods ptm,hsh9,rbf,bilinear] [--planes N]
//                       [--grid-size G] [--rbf-width DEG] [--rbf-regularisation R]
//
// (default: DiLiGenT cat from $PHOTOMAT_TEST_DATA, K = 10, i.e. lights 0, 10, .. 90 held out.)
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "capture/io/load_photometric_set.h"
#include "core/error.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/observations.h"

namespace photomat {
namespace {

struct Arguments {
  std::filesystem::path set;
  int every = 10;
  std::string methods = "ptm,hsh9,eigen6,rbf,bilinear";
  LightProfileOptions profile;
};

Arguments Parse(int argc, char** argv) {
  Arguments arguments;
  if (const char* data = std::getenv("PHOTOMAT_TEST_DATA")) {
    arguments.set = std::filesystem::path(data) / "diligent" / "cat";
  }
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error(fmt::format("{} needs a value", a));
      return argv[++i];
    };
    if (a == "--every") {
      arguments.every = std::stoi(value());
    } else if (a == "--methods") {
      arguments.methods = value();
    } else if (a == "--planes") {
      arguments.profile.planes = std::stoi(value());
    } else if (a == "--grid-size") {
      arguments.profile.grid_size = std::stoi(value());
    } else if (a == "--rbf-width") {
      arguments.profile.rbf_width_degrees = std::stod(value());
    } else if (a == "--rbf-regularisation") {
      arguments.profile.rbf_regularisation = std::stod(value());
    } else {
      arguments.set = a;
    }
  }
  if (arguments.set.empty()) throw Error("no set given and PHOTOMAT_TEST_DATA is not set");
  if (arguments.every < 2) throw Error("--every must be at least 2");
  return arguments;
}

int Run(int argc, char** argv) {
  const Arguments arguments = Parse(argc, argv);
  const LoadedSet loaded = LoadPhotometricSet(arguments.set);
  const Observations observations(loaded.set);
  std::vector<int> held_out, selected;
  for (int i = 0; i < loaded.set.size(); ++i) {
    (i % arguments.every == 0 ? held_out : selected).push_back(i);
  }
  const float peak = observations.matrix().maxCoeff();
  fmt::print("{}: {} images, {} pixels; {} held out (every {}th), peak {:.4g}\n",
             arguments.set.string(), loaded.set.size(), observations.pixels(), held_out.size(),
             arguments.every, peak);
  fmt::print(
      "| method | PSNR dB | eta | planes x channels | fit s |\n| --- | ---: | ---: | ---: | ---: "
      "|\n");
  std::vector<Method> methods = ParseMethodList(arguments.methods);
  for (Method& method : methods) {
    method.profile = arguments.profile;
    const auto start = std::chrono::steady_clock::now();
    const Representation r =
        FitObservations(observations, loaded.set.lights(), method, selected, loaded.set.source());
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    double psnr = 0.0, eta = 0.0;
    for (int i : held_out) {
      const Eigen::VectorXf relit = RelightObservedPixels(r, observations, loaded.set.light(i));
      eta += NormalisedRmsError(observations, i, relit);
      const Eigen::ArrayXf a = relit.array().max(0.0f).min(peak);
      const Eigen::ArrayXf b = observations.matrix().col(i).array().max(0.0f).min(peak);
      const double mse = (a - b).square().cast<double>().mean();
      psnr += 10.0 * std::log10(double{peak} * peak / mse);
    }
    const auto count = static_cast<double>(held_out.size());
    fmt::print("| {} | {:.2f} | {:.4f} | {} | {:.1f} |\n", method.Name(), psnr / count, eta / count,
               r.maps().channels(), seconds);
    if (r.details().contains("rbf")) {
      fmt::print("  rbf width {:.3g} deg, regularisation {:.3g}\n",
                 r.details()["rbf"]["width_deg"].get<double>(),
                 r.details()["rbf"]["regularisation"].get<double>());
    }
  }
  return 0;
}

}  // namespace
}  // namespace photomat

int main(int argc, char** argv) {
  try {
    return photomat::Run(argc, argv);
  } catch (const std::exception& error) {
    fmt::print(stderr, "held_out_lights: {}\n", error.what());
    return 1;
  }
}
