#include "synthesize/mesh/mesh_render.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/colour.h"
#include "core/error.h"
#include "core/image_io.h"

namespace photomat {

std::vector<PreviewView> DefaultPreviewViews() {
  return {{"front", 0.0, 20.0},
          {"right", 90.0, 20.0},
          {"back", 180.0, 20.0},
          {"left", 270.0, 20.0},
          {"top", 0.0, 89.0}};
}

namespace {

// Camera axes: right, up and toward-the-viewer unit vectors.
struct Camera {
  Eigen::Vector3d right, up, toward;
};

Camera MakeCamera(const PreviewView& view) {
  const double az = view.azimuth_degrees * std::numbers::pi / 180.0;
  const double el = view.elevation_degrees * std::numbers::pi / 180.0;
  Camera camera;
  camera.toward =
      Eigen::Vector3d(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
  camera.right = Eigen::Vector3d::UnitY().cross(camera.toward).normalized();
  camera.up = camera.toward.cross(camera.right);
  return camera;
}

}  // namespace

Image RenderPreview(const TriangleMesh& mesh, std::span<const Eigen::Vector3f> linear_colours,
                    const PreviewView& view, const PreviewOptions& options) {
  if (options.size < 8 || options.size > 8192) throw Error("preview size must be in 8..8192");
  if (!linear_colours.empty() &&
      linear_colours.size() != static_cast<std::size_t>(mesh.vertex_count())) {
    throw Error(fmt::format("preview: {} colours for {} vertices", linear_colours.size(),
                            mesh.vertex_count()));
  }
  const int size = options.size;
  Image image(size, size, {"R", "G", "B"});
  for (std::size_t i = 0; i < image.pixel_count(); ++i) {
    for (int c = 0; c < 3; ++c) image.pixel(i)[c] = options.background[c];
  }
  if (mesh.positions.empty()) return image;

  const Camera camera = MakeCamera(view);
  const BoundingBox box = ComputeBoundingBox(mesh);
  // The bounding sphere fills 90 % of the frame whatever the view.
  const double scale = 0.9 * size / std::max(box.Diagonal(), 1e-300);
  const Eigen::Vector3d centre = box.Centre();
  const int n = mesh.vertex_count();
  std::vector<Eigen::Vector3d> screen(n);  // x right, y down (pixels), depth toward viewer
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d d = mesh.positions[v] - centre;
    screen[v] = {0.5 * size + scale * d.dot(camera.right), 0.5 * size - scale * d.dot(camera.up),
                 d.dot(camera.toward)};
  }
  const auto normals = VertexNormals(mesh);
  // Key light from the upper left of the viewer.
  const Eigen::Vector3d light = (camera.toward + 0.5 * camera.up - 0.4 * camera.right).normalized();
  const Eigen::Vector3f grey = Eigen::Vector3f::Constant(0.6f);
  std::vector<double> depth(image.pixel_count(), -std::numeric_limits<double>::infinity());

  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = screen[t[0]];
    const Eigen::Vector3d& b = screen[t[1]];
    const Eigen::Vector3d& c = screen[t[2]];
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(size - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(size - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        // Barycentric weights by edge functions (either winding).
        const double wa = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
        const double wb = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
        const double wc = 1.0 - wa - wb;
        if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
        const double z = wa * a.z() + wb * b.z() + wc * c.z();
        const std::size_t index = static_cast<std::size_t>(y) * size + x;
        if (z <= depth[index]) continue;
        depth[index] = z;
        Eigen::Vector3d normal = wa * normals[t[0]] + wb * normals[t[1]] + wc * normals[t[2]];
        if (normal.dot(camera.toward) < 0.0) normal = -normal;  // back face
        const double lambert = std::max(0.0, normal.normalized().dot(light));
        const float shade =
            options.ambient + (1.0f - options.ambient) * static_cast<float>(lambert);
        Eigen::Vector3f colour = grey;
        if (!linear_colours.empty()) {
          colour = static_cast<float>(wa) * linear_colours[t[0]] +
                   static_cast<float>(wb) * linear_colours[t[1]] +
                   static_cast<float>(wc) * linear_colours[t[2]];
        }
        for (int ch = 0; ch < 3; ++ch) image.pixel(index)[ch] = shade * colour[ch];
      }
    }
  }
  return image;
}

std::vector<std::filesystem::path> WritePreviews(const std::filesystem::path& folder,
                                                 const std::string& prefix,
                                                 const TriangleMesh& mesh,
                                                 std::span<const Eigen::Vector3f> linear_colours,
                                                 const std::vector<PreviewView>& views,
                                                 const PreviewOptions& options) {
  std::vector<std::filesystem::path> written;
  ImageWriteOptions write;
  write.sample_type = SampleType::kUint8;
  write.encoding = ColourSpace::kSrgb;
  for (const auto& view : views) {
    const auto path = folder / fmt::format("{}_{}.png", prefix, view.name);
    WriteImage(path, RenderPreview(mesh, linear_colours, view, options), write);
    written.push_back(path);
  }
  return written;
}

}  // namespace photomat
