#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image.h"

namespace photomat {

// The deep-zoom form of a method's maps in the web viewer (README "Web viewer and evaluation
// report"): a multi-resolution pyramid of tiles of every coefficient plane, of which the viewer
// loads only the tiles in view. Level 0 is the stack; level L + 1 is level L halved (each pixel the
// average of a 2 x 2 block, or of the 2 or 1 pixels a block holds at an odd right or bottom edge),
// until the whole level fits one tile. Each level is cut into tiles of tile_size x tile_size
// pixels, each stored with `overlap` pixels of its neighbours on every side that has one
// (DeepZoom's convention), so that a bilinear lookup at a tile's edge needs no other tile:
//
//   <folder>/<L>/<column>_<row>.f32
//
// A tile holds ceil(maps / 4) RGBA layers of its width x height texels, layer-major, rows from the
// top, float32 little-endian: the texture layout of the whole-image maps/<method>.f32.
//
// IMPLEMENTER CHOICE: tiles are raw float32, not 16-bit PNGs with a scale and bias per plane:
// relighting computes in float32, so the viewer's pixels then equal `photomat relight`'s (as for
// untiled stacks), and PNG's 16 bits would put a quantisation of up to 1 / 65535 of each plane's
// range on every coefficient (PTM's quadratic terms span ranges far wider than their
// contribution). The cost is size: 4 bytes per coefficient, uncompressed (a server's gzip halves
// it).
//
// Coarser levels average the coefficient planes, not relit images: every linear method the viewer
// shows is linear in its maps (out = sum_j c_j(l) B_j, or with a gain map a product the viewer also
// forms per pixel), so the average of a block's coefficients relights to the average of the
// block's relit values (exactly for methods without a gain, and for gain methods to the product
// of averages). A neural stack's decoder is not linear: its coarser levels relight to the
// decoding of averaged coefficients, close to but not exactly the average (README). pbr is refused.

// Appends `value` as float32 little-endian: the number format of every viewer data file.
void AppendFloat32(std::string& bytes, float value);

// The values of a file of float32 little-endian values (a viewer map, table or tile, as
// AppendFloat32 writes them). Throws Error naming the file when its size is not a whole number
// of values.
std::vector<float> ReadFloat32File(const std::filesystem::path& path);

// When `photomat export --viewer` writes tiles (--viewer-tiles).
enum class ViewerTiling { kAuto, kAlways, kNever };
ViewerTiling ParseViewerTiling(const std::string& text);
std::string ToString(ViewerTiling tiling);

// IMPLEMENTER CHOICE: kAuto tiles stacks of more than 4096 x 4096 pixels. Below, one RGBA32F
// texture of the whole stack (up to 16 MP x 16 bytes a layer: 256 MB a layer) loads in seconds
// and every WebGL2 browser takes it; above, a 48 MP Eigen-6 stack (5 layers) would be 3.9 GB of
// download and texture before the first pixel shows. (The whole-texture path stops at 8192 pixels
// a side in any case.)
inline constexpr std::int64_t kViewerTilingThresholdPixels = std::int64_t{4096} * 4096;
// IMPLEMENTER CHOICE: 256 x 256 tiles with 1 pixel of overlap (DeepZoom's defaults): a tile of
// 5 layers is 1.3 MB, a 1200 x 800 view needs about 24 of them.
inline constexpr int kViewerTileSize = 256;
inline constexpr int kViewerTileOverlap = 1;

// Whether a width x height stack is exported as tiles under `tiling`.
bool UsesViewerTiles(ViewerTiling tiling, int width, int height);

// A tile's pixels in its level: [x, x + width) x [y, y + height), overlap included.
struct TileRect {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
};

// The geometry of a pyramid: its levels' sizes and their tiles.
class PyramidLayout {
 public:
  // Throws Error unless the sizes are positive and tile_size > 2 * overlap.
  PyramidLayout(int width, int height, int tile_size = kViewerTileSize,
                int overlap = kViewerTileOverlap);

  int width() const { return width_; }
  int height() const { return height_; }
  int tile_size() const { return tile_size_; }
  int overlap() const { return overlap_; }
  int levels() const { return static_cast<int>(level_sizes_.size()); }
  int LevelWidth(int level) const { return level_sizes_.at(level).first; }
  int LevelHeight(int level) const { return level_sizes_.at(level).second; }
  int Columns(int level) const;
  int Rows(int level) const;
  std::size_t TileCount() const;
  // The bytes of every tile file of a pyramid of `maps` maps (for the disk space check).
  std::size_t FileBytes(int maps) const;
  TileRect Tile(int level, int column, int row) const;
  // "<level>/<column>_<row>.f32", relative to the pyramid's folder.
  static std::string TilePath(int level, int column, int row);
  // {"width", "height", "tile_size", "overlap", "levels", "format": "float32",
  //  "level_sizes": [[w, h], ...]}
  nlohmann::json ToJson() const;

 private:
  int width_;
  int height_;
  int tile_size_;
  int overlap_;
  std::vector<std::pair<int, int>> level_sizes_;
};

// Writes a pyramid from the rows of level 0, given in order in bands of any height: holds one row
// of tiles (tile_size + 2 * overlap rows) of each level and a row pair being averaged, never the
// whole stack (BufferBytes).
class PyramidWriter {
 public:
  // `folder` must exist; `maps` planes per pixel.
  PyramidWriter(std::filesystem::path folder, PyramidLayout layout, int maps);

  // The next rows of level 0: `rows` has the layout's width and `maps` channels.
  void AddRows(ConstImageView rows);
  // Throws Error unless every row of level 0 has been given (then every tile is written).
  void Finish();

  // The bytes the writer holds at most besides the rows given to it.
  static std::size_t BufferBytes(const PyramidLayout& layout, int maps);

 private:
  // One level being filled: rows from `first_row` in `rows`, each planar (map * width + x).
  struct Level {
    int width = 0;
    int height = 0;
    int received = 0;  // rows given so far
    int tile_row = 0;  // the row of tiles being filled
    int first_row = 0;
    std::vector<std::vector<float>> rows;
    std::vector<float> pending;  // an even row waiting for its pair (for the next level)
  };

  void AddLevelRow(int level, std::vector<float> row);
  void WriteTileRow(int level);
  std::vector<float> HalveRow(const Level& from, const std::vector<float>& upper,
                              const std::vector<float>* lower) const;

  std::filesystem::path folder_;
  PyramidLayout layout_;
  int maps_;
  std::vector<Level> levels_;
};

}  // namespace photomat
