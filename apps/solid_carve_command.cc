// photomat solid carve: objects carved out of solid textures (needs solids and meshes:
// PHOTOMAT_WITH_SOLIDS and PHOTOMAT_WITH_SURFACE_PATTERNS).
#include "apps/solid_carve_command.h"

#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/solid_command.h"
#include "core/atomic_file.h"
#include "core/json_file.h"
#include "core/progress.h"
#include "synthesize/carving/solid_carving.h"
#include "synthesize/mesh/mesh_io.h"
#include "synthesize/mesh/mesh_render.h"
#include "synthesize/volume/volume.h"
#include "synthesize/volume/volume_io.h"

namespace photomat::app {

namespace {

struct CarveCommandOptions {
  std::filesystem::path volume, mesh, out;
  CarveOptions carve;
  bool clamp = false;
  bool normalise = false;
  int preview_size = 512;
  int threads = 0;
};

void AddCarveOptions(CLI::App& command, CarveCommandOptions& options) {
  command.add_option("volume", options.volume, "Solid texture: FILE.vdb or an EXR slice folder")
      ->required();
  command.add_option("--mesh", options.mesh, "Mesh file (OBJ, PLY, OFF, STL, ...)")->required();
  command.add_option("--out", options.out, "Output folder")->required();
  command
      .add_option("--periods", options.carve.placement.periods,
                  "Volume periods across the mesh's longest side (above 1 repeats the volume)")
      ->capture_default_str();
  command.add_flag("--clamp", options.clamp,
                   "The volume does not tile: repeat its faces instead of wrapping around");
  command
      .add_option("--max-edge", options.carve.max_mean_edge_voxels,
                  "Subdivide until the mean edge is at most this many voxels (0: never)")
      ->capture_default_str();
  command.add_flag("--normalise", options.normalise,
                   "Stretch the shown channels' range over the colours (non-colour volumes)");
  command.add_option("--preview-size", options.preview_size, "Preview side, pixels")
      ->capture_default_str();
  command.add_option("--threads", options.threads, "Threads (0: all; same result any count)")
      ->capture_default_str();
}

// Every channel at every vertex, as CSV under the channels' names (representation maps carry
// more than a colour).
std::string VertexValuesCsv(const CarvedMesh& carved, const std::vector<std::string>& names) {
  std::string table;
  for (std::size_t c = 0; c < names.size(); ++c) table += (c ? "," : "") + names[c];
  table += "\n";
  for (int v = 0; v < carved.mesh.vertex_count(); ++v) {
    const auto values = carved.at(v);
    for (std::size_t c = 0; c < values.size(); ++c) {
      table += fmt::format("{}{:.6g}", c ? "," : "", values[c]);
    }
    table += "\n";
  }
  return table;
}

void RunCarve(const CarveCommandOptions& options) {
  const auto limit = LimitThreads(options.threads);
  const Image volume = ReadVolume(options.volume);
  const TriangleMesh mesh = ReadMesh(options.mesh);
  CarveOptions carve = options.carve;
  carve.placement.tileable = !options.clamp;
  TerminalProgressBar bar;
  const auto start = std::chrono::steady_clock::now();
  const CarvedMesh carved = CarveMesh(mesh, volume, carve, &bar);
  const std::vector<Eigen::Vector3f> colours = CarvedColours(carved, volume, options.normalise);
  fmt::print(
      "carved {} ({} vertices, {} subdivision levels: {} vertices) out of a {} solid "
      "({:.2f} s)\n",
      options.mesh.filename().string(), mesh.vertex_count(), carved.subdivision_levels,
      carved.mesh.vertex_count(), ToString(volume.extent()), Seconds(start));
  CreateFolder(options.out);
  WriteMesh(options.out / "carved.ply", carved.mesh, colours);
  WriteMesh(options.out / "carved.glb", carved.mesh, colours);
  const std::vector<std::string> names = ChannelNamesOrDefault(volume);
  WriteTextFileAtomically(options.out / "vertex_values.csv", VertexValuesCsv(carved, names));
  PreviewOptions preview;
  preview.size = options.preview_size;
  const std::vector<PreviewView> views = DefaultPreviewViews();
  bar.Start("preview renders", views.size());
  for (const PreviewView& view : views) {
    WritePreviews(options.out, "preview", carved.mesh, colours, {view}, preview);
    bar.Advance();
  }
  bar.Finish();
  const CarveMapping& mapping = carved.mapping;
  WriteJsonFile(
      options.out / "carve.json",
      {{"volume", options.volume.string()},
       {"volume_size", ToString(volume.extent())},
       {"channels", names},
       {"mesh", options.mesh.string()},
       {"input_vertices", mesh.vertex_count()},
       {"subdivision_levels", carved.subdivision_levels},
       {"vertices", carved.mesh.vertex_count()},
       {"triangles", carved.mesh.triangle_count()},
       {"mean_edge_voxels", MeanEdgeLength(carved.mesh) * mapping.scale},
       {"periods", carve.placement.periods},
       {"tileable", carve.placement.tileable},
       {"scale_voxels_per_unit", mapping.scale},
       {"mesh_centre", {mapping.mesh_centre.x(), mapping.mesh_centre.y(), mapping.mesh_centre.z()}},
       {"volume_centre",
        {mapping.volume_centre.x(), mapping.volume_centre.y(), mapping.volume_centre.z()}}});
  fmt::print(
      "wrote carved.ply, carved.glb, vertex_values.csv, {} previews and carve.json to "
      "{}\n",
      views.size(), options.out.string());
}

}  // namespace

void AddSolidCarveCommand(CLI::App& solid, std::string_view description) {
  BindCommand(*solid.add_subcommand("carve", std::string(description)), AddCarveOptions, RunCarve);
}

}  // namespace photomat::app
