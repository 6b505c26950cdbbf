#include "apps/generate_command.h"

#include <fmt/format.h>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "core/error.h"

namespace photomat::app {

void AddGenerateCommand(CLI::App& app) {
  struct Options {
    std::filesystem::path out;
    std::string size = "128x128";
    std::string pattern = "bricks";
    std::string lights;
    std::string roughness = "0.35,0.65";
    std::string f0 = "0.04,0.08";
    GenerateOptions generate;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = AddListedCommand(app, "generate");
  command->add_option("--out", options->out, "Output folder")->required();
  command->add_option("--size", options->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  command->add_option("--pattern", options->pattern, "Material: bricks, bumps or grooves")
      ->capture_default_str();
  command
      ->add_option("--relief", options->generate.material.max_slope_degrees,
                   "Steepest surface slope in degrees (25 casts no shadow on the default "
                   "lights; 50+ makes shadows)")
      ->capture_default_str();
  command->add_flag("--shadows", options->generate.render.shadows,
                    "Attached and cast shadows (off: the linear Lambertian model)");
  command
      ->add_option("--specular", options->generate.render.specular,
                   "Blinn-Phong specular coefficient k_s (0: Lambertian)")
      ->capture_default_str();
  command->add_option("--shininess", options->generate.render.shininess, "Blinn-Phong exponent")
      ->capture_default_str();
  command->add_flag("--ggx", options->generate.render.microfacet,
                    "GGX microfacet material (the model `fit --method pbr` fits): base colour = "
                    "the albedo, roughness and F0 maps from the ranges below");
  command
      ->add_option("--roughness", options->roughness,
                   "GGX perceptual roughness range MIN,MAX (alpha = roughness^2)")
      ->capture_default_str();
  command->add_option("--f0", options->f0, "GGX Fresnel reflectance F0 range MIN,MAX")
      ->capture_default_str();
  command
      ->add_option("--noise", options->generate.render.noise_sigma,
                   "Gaussian noise sigma, in units of full scale")
      ->capture_default_str();
  command
      ->add_option("--seed", options->generate.material.seed, "Seed of the material and the noise")
      ->capture_default_str();
  command->add_option("--lights", options->lights,
                      "Light file (.lp, manifest.json, DiLiGenT folder); default: the thesis grid "
                      "(12 tilts x slants 30, 45, 60)");
  command->add_flag("--exr", options->generate.exr, "Write float EXR images instead of 16-bit PNG");
  command->callback([options] {
    GenerateOptions generate = options->generate;
    std::tie(generate.material.width, generate.material.height) = ParseSize(options->size);
    const auto pattern = ParseSurfacePattern(options->pattern);
    if (!pattern) {
      throw Error(fmt::format("unknown pattern \"{}\": expected bricks, bumps or grooves",
                              options->pattern));
    }
    generate.material.pattern = *pattern;
    std::tie(generate.material.roughness_min, generate.material.roughness_max) =
        ParseRange("--roughness", options->roughness);
    std::tie(generate.material.f0_min, generate.material.f0_max) = ParseRange("--f0", options->f0);
    generate.render.noise_seed = generate.material.seed;
    if (!options->lights.empty()) generate.lights = options->lights;
    const int images = WriteSyntheticSet(options->out, generate);
    fmt::print("wrote {} images of a {}x{} {} sample with ground truth to {}\n", images,
               generate.material.width, generate.material.height, options->pattern,
               options->out.string());
  });
}

}  // namespace photomat::app
