#include "relight/web/viewer_pyramid.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstdint>

#include "core/atomic_file.h"
#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

int HalfUp(int n) { return (n + 1) / 2; }

}  // namespace

void AppendFloat32(std::string& bytes, float value) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  for (int b = 0; b < 4; ++b)
    bytes += static_cast<char>((bits >> (8 * b)) & 0xff);  // little-endian
}

std::vector<float> ReadFloat32File(const std::filesystem::path& path) {
  const std::string bytes = ReadTextFile(path);
  if (bytes.size() % 4 != 0) {
    throw Error(path,
                fmt::format("{} bytes is not a whole number of float32 values", bytes.size()));
  }
  std::vector<float> values(bytes.size() / 4);
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint32_t bits = 0;
    for (int b = 0; b < 4; ++b) {
      bits |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[4 * i + b])) << (8 * b);
    }
    values[i] = std::bit_cast<float>(bits);
  }
  return values;
}

ViewerTiling ParseViewerTiling(const std::string& text) {
  if (text == "auto") return ViewerTiling::kAuto;
  if (text == "always") return ViewerTiling::kAlways;
  if (text == "never") return ViewerTiling::kNever;
  throw Error(fmt::format("--viewer-tiles: expected auto, always or never, not \"{}\"", text));
}

std::string ToString(ViewerTiling tiling) {
  switch (tiling) {
    case ViewerTiling::kAlways:
      return "always";
    case ViewerTiling::kNever:
      return "never";
    case ViewerTiling::kAuto:
      break;
  }
  return "auto";
}

bool UsesViewerTiles(ViewerTiling tiling, int width, int height) {
  if (tiling != ViewerTiling::kAuto) return tiling == ViewerTiling::kAlways;
  return static_cast<std::int64_t>(width) * height > kViewerTilingThresholdPixels;
}

PyramidLayout::PyramidLayout(int width, int height, int tile_size, int overlap)
    : width_(width), height_(height), tile_size_(tile_size), overlap_(overlap) {
  if (width <= 0 || height <= 0) {
    throw Error(
        fmt::format("a tile pyramid of {}x{} pixels: the sizes must be positive", width, height));
  }
  if (overlap < 0 || tile_size <= 2 * overlap) {
    throw Error(
        fmt::format("tiles of {} pixels with an overlap of {}: the tile size must exceed "
                    "twice the overlap",
                    tile_size, overlap));
  }
  level_sizes_.emplace_back(width, height);
  while (std::max(level_sizes_.back().first, level_sizes_.back().second) > tile_size) {
    level_sizes_.emplace_back(HalfUp(level_sizes_.back().first),
                              HalfUp(level_sizes_.back().second));
  }
}

int PyramidLayout::Columns(int level) const {
  return (LevelWidth(level) + tile_size_ - 1) / tile_size_;
}

int PyramidLayout::Rows(int level) const {
  return (LevelHeight(level) + tile_size_ - 1) / tile_size_;
}

std::size_t PyramidLayout::TileCount() const {
  std::size_t count = 0;
  for (int level = 0; level < levels(); ++level) {
    count += static_cast<std::size_t>(Columns(level)) * Rows(level);
  }
  return count;
}

std::size_t PyramidLayout::FileBytes(int maps) const {
  std::size_t texels = 0;
  for (int level = 0; level < levels(); ++level) {
    for (int row = 0; row < Rows(level); ++row) {
      for (int column = 0; column < Columns(level); ++column) {
        const TileRect t = Tile(level, column, row);
        texels += static_cast<std::size_t>(t.width) * t.height;
      }
    }
  }
  return texels * 16 * static_cast<std::size_t>((maps + 3) / 4);
}

TileRect PyramidLayout::Tile(int level, int column, int row) const {
  const int x0 = std::max(column * tile_size_ - overlap_, 0);
  const int y0 = std::max(row * tile_size_ - overlap_, 0);
  const int x1 = std::min((column + 1) * tile_size_ + overlap_, LevelWidth(level));
  const int y1 = std::min((row + 1) * tile_size_ + overlap_, LevelHeight(level));
  return {x0, y0, x1 - x0, y1 - y0};
}

std::string PyramidLayout::TilePath(int level, int column, int row) {
  return fmt::format("{}/{}_{}.f32", level, column, row);
}

nlohmann::json PyramidLayout::ToJson() const {
  nlohmann::json sizes = nlohmann::json::array();
  for (const auto& [w, h] : level_sizes_) sizes.push_back({w, h});
  return {{"width", width_},     {"height", height_},  {"tile_size", tile_size_},
          {"overlap", overlap_}, {"levels", levels()}, {"format", "float32"},
          {"level_sizes", sizes}};
}

PyramidWriter::PyramidWriter(fs::path folder, PyramidLayout layout, int maps)
    : folder_(std::move(folder)), layout_(std::move(layout)), maps_(maps) {
  if (maps <= 0) throw Error(folder_, "a tile pyramid needs at least one map");
  for (int level = 0; level < layout_.levels(); ++level) {
    Level l;
    l.width = layout_.LevelWidth(level);
    l.height = layout_.LevelHeight(level);
    levels_.push_back(std::move(l));
    std::error_code ec;
    fs::create_directories(folder_ / std::to_string(level), ec);
    if (ec) throw Error(folder_ / std::to_string(level), "cannot create folder: " + ec.message());
  }
}

std::size_t PyramidWriter::BufferBytes(const PyramidLayout& layout, int maps) {
  // Per level: a row of tiles with its overlaps, the pending row and the row being made.
  std::size_t floats = 0;
  for (int level = 0; level < layout.levels(); ++level) {
    const std::size_t rows = static_cast<std::size_t>(layout.tile_size()) +
                             2 * static_cast<std::size_t>(layout.overlap()) + 2;
    floats += rows * static_cast<std::size_t>(layout.LevelWidth(level)) * maps;
  }
  // A tile being serialised: 4 channels a layer.
  const std::size_t tile_side = layout.tile_size() + 2 * layout.overlap();
  floats += tile_side * tile_side * 4 * static_cast<std::size_t>((maps + 3) / 4);
  return 4 * floats;
}

void PyramidWriter::AddRows(ConstImageView rows) {
  if (rows.width() != layout_.width() || rows.channels() != maps_) {
    throw Error(folder_, fmt::format("rows of {} pixels and {} maps given to a pyramid of {} "
                                     "pixels and {} maps",
                                     rows.width(), rows.channels(), layout_.width(), maps_));
  }
  for (int y = 0; y < rows.height(); ++y) {
    std::vector<float> row(static_cast<std::size_t>(maps_) * rows.width());
    for (int m = 0; m < maps_; ++m) {
      const auto values = rows.row(m, y);
      std::copy(values.begin(), values.end(),
                row.begin() + static_cast<std::ptrdiff_t>(m) * rows.width());
    }
    AddLevelRow(0, std::move(row));
  }
}

void PyramidWriter::Finish() {
  if (levels_[0].received != levels_[0].height) {
    throw Error(folder_, fmt::format("a tile pyramid of {} rows was given {}", levels_[0].height,
                                     levels_[0].received));
  }
}

// The row of the next level made from `upper` and `lower` (none at an odd bottom edge): the
// average of each 2 x 2 block, or of the pixels a block at the right or bottom edge holds.
std::vector<float> PyramidWriter::HalveRow(const Level& from, const std::vector<float>& upper,
                                           const std::vector<float>* lower) const {
  const int half = HalfUp(from.width);
  std::vector<float> out(static_cast<std::size_t>(maps_) * half);
  for (int m = 0; m < maps_; ++m) {
    const std::size_t in = static_cast<std::size_t>(m) * from.width;
    for (int x = 0; x < half; ++x) {
      const int x0 = 2 * x, x1 = std::min(2 * x + 1, from.width - 1);
      // Summed in double: the same value whatever the order, for the tests' box averages.
      double sum = static_cast<double>(upper[in + x0]);
      int count = 1;
      if (x1 != x0) sum += upper[in + x1], ++count;
      if (lower) {
        sum += (*lower)[in + x0], ++count;
        if (x1 != x0) sum += (*lower)[in + x1], ++count;
      }
      out[static_cast<std::size_t>(m) * half + x] = static_cast<float>(sum / count);
    }
  }
  return out;
}

void PyramidWriter::AddLevelRow(int level, std::vector<float> row) {
  Level& l = levels_[level];
  if (l.received >= l.height) {
    throw Error(folder_, fmt::format("level {} of the tile pyramid was given more than its {} rows",
                                     level, l.height));
  }
  const int y = l.received++;
  if (level + 1 < layout_.levels()) {
    if (y % 2 == 0 && y + 1 < l.height) {
      l.pending = row;
    } else {
      std::vector<float> half =
          y % 2 == 0 ? HalveRow(l, row, nullptr) : HalveRow(l, l.pending, &row);
      l.pending.clear();
      AddLevelRow(level + 1, std::move(half));
    }
  }
  Level& same = levels_[level];  // AddLevelRow of the next level does not move this one
  same.rows.push_back(std::move(row));
  const int T = layout_.tile_size(), overlap = layout_.overlap();
  const int end = std::min((same.tile_row + 1) * T + overlap, same.height);
  if (same.received == end) {
    WriteTileRow(level);
    // Keep the rows the next row of tiles starts with (its top overlap).
    const int next_first = std::max((same.tile_row + 1) * T - overlap, 0);
    const int drop = std::clamp(next_first - same.first_row, 0, static_cast<int>(same.rows.size()));
    same.rows.erase(same.rows.begin(), same.rows.begin() + drop);
    same.first_row += drop;
    ++same.tile_row;
  }
}

void PyramidWriter::WriteTileRow(int level) {
  const Level& l = levels_[level];
  const int layers = (maps_ + 3) / 4;
  for (int column = 0; column < layout_.Columns(level); ++column) {
    const TileRect tile = layout_.Tile(level, column, l.tile_row);
    std::string bytes;
    bytes.reserve(static_cast<std::size_t>(layers) * tile.width * tile.height * 16);
    for (int layer = 0; layer < layers; ++layer) {
      for (int y = tile.y; y < tile.y + tile.height; ++y) {
        const std::vector<float>& row = l.rows.at(static_cast<std::size_t>(y - l.first_row));
        for (int x = tile.x; x < tile.x + tile.width; ++x) {
          for (int c = 0; c < 4; ++c) {
            const int map = 4 * layer + c;
            AppendFloat32(bytes,
                          map < maps_ ? row[static_cast<std::size_t>(map) * l.width + x] : 0.0f);
          }
        }
      }
    }
    WriteTextFileAtomically(folder_ / PyramidLayout::TilePath(level, column, l.tile_row), bytes);
  }
}

}  // namespace photomat
