#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "core/image.h"
#include "synthesize/mesh/mesh.h"

namespace photomat {

// Preview renders of a coloured mesh: an orthographic z-buffer rasteriser with per-vertex colours
// interpolated across triangles and Lambertian shading by a light over the viewer's shoulder.
// (IMPLEMENTER CHOICE: written here, ~100 lines, because no Debian package rasterises headless
// without an OpenGL context; OSMesa would need one plus a GL pipeline for a few views.)

// A camera direction around the mesh's bounding-box centre, with +y up: azimuth 0 looks along -z
// (from +z), 90 from +x; elevation raises the camera toward +y.
struct PreviewView {
  std::string name;
  double azimuth_degrees = 0.0;
  double elevation_degrees = 0.0;
};
// front, right, back, left (elevation 20) and top.
std::vector<PreviewView> DefaultPreviewViews();

struct PreviewOptions {
  int size = 512;                                                // square image, pixels
  Eigen::Vector3f background = Eigen::Vector3f::Constant(1.0f);  // linear RGB
  float ambient = 0.25f;                                         // unlit share of the colour
};

// A size x size linear RGB image ("R", "G", "B"). `linear_colours` has one colour per vertex
// (empty: light grey). Back faces are shaded as front faces, so open meshes show their insides.
Image RenderPreview(const TriangleMesh& mesh, std::span<const Eigen::Vector3f> linear_colours,
                    const PreviewView& view, const PreviewOptions& options = {});

// One sRGB PNG per view, `folder/<prefix>_<view>.png`; returns the paths written.
std::vector<std::filesystem::path> WritePreviews(const std::filesystem::path& folder,
                                                 const std::string& prefix,
                                                 const TriangleMesh& mesh,
                                                 std::span<const Eigen::Vector3f> linear_colours,
                                                 const std::vector<PreviewView>& views,
                                                 const PreviewOptions& options = {});

}  // namespace photomat
