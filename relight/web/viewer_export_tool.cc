// viewer_export_tool FIT_FOLDER OUT_DIR [--table METHOD,...] [--title TEXT]
//
// Test tooling for the browser test (viewer/test): exports the stacks of a `photomat fit` folder
// to a web viewer with ExportViewer, optionally forcing the coefficient table for some methods.
// `photomat export STACK --viewer DIR` is the user-facing entry point.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <set>
#include <string>

#include "core/error.h"
#include "relight/web/viewer_export.h"
#include "represent/model/method.h"
#include "represent/stack/map_stack.h"

int main(int argc, char** argv) {
  using namespace photomat;
  try {
    if (argc < 3)
      throw Error("usage: viewer_export_tool FIT_FOLDER OUT_DIR [--table M,...] [--title T]");
    ViewerExportOptions options;
    for (int i = 3; i + 1 < argc; i += 2) {
      const std::string flag = argv[i], value = argv[i + 1];
      if (flag == "--title") {
        options.title = value;
      } else if (flag == "--table") {
        std::size_t start = 0;
        while (start <= value.size()) {
          const std::size_t comma = std::min(value.find(',', start), value.size());
          if (comma > start) options.table_methods.insert(value.substr(start, comma - start));
          start = comma + 1;
        }
      } else {
        throw Error(fmt::format("unknown option {}", flag));
      }
    }
    // The methods in the order of photomat's own list (3i, gradient, ptm, ...), others after.
    const auto stacks = ReadFitManifest(argv[1]);
    std::vector<std::pair<std::string, std::filesystem::path>> ordered;
    for (const Method& method : AllMethods()) {
      if (stacks.contains(method.Name()))
        ordered.emplace_back(method.Name(), stacks.at(method.Name()));
    }
    for (const auto& [method, path] : stacks) {
      if (std::none_of(ordered.begin(), ordered.end(),
                       [&](const auto& o) { return o.first == method; })) {
        ordered.emplace_back(method, path);
      }
    }
    std::vector<Representation> representations;
    for (const auto& [method, path] : ordered) {
      LoadedStack stack = LoadRepresentation(path);
      if (options.capture_lights.empty()) options.capture_lights = stack.provenance.capture_lights;
      representations.push_back(std::move(stack.representation));
    }
    ExportViewer(argv[2], representations, options);
    fmt::print("wrote the viewer for {} method(s) to {}\n", representations.size(), argv[2]);
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "viewer_export_tool: error: %s\n", error.what());
    return 1;
  }
}
