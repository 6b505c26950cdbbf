#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "apps/batch/child_process.h"

namespace photomat::batch::testing {

// A small collection for the batch command tests: synthetic captures made by `photomat
// generate`, some broken on purpose, one recipe for all, and the by-hand commands its tasks must
// equal.

enum class CaptureFault { kNone, kMissingImage, kMalformedLp };

struct TestCapture {
  std::string name;
  std::string size = "32x24";
  int seed = 1;
  CaptureFault fault = CaptureFault::kNone;
};

// Eight 32x24 captures, capture-0 to capture-7; capture-3 misses an image, capture-6 has a
// malformed .lp (the must-show collection of `batch run` and of the Slurm array).
std::vector<TestCapture> EightCapturesTwoBroken();

// `photomat ARGUMENTS` with `folder` as working directory (created), output collected.
ChildOutcome RunPhotomatIn(const std::filesystem::path& folder,
                           const std::vector<std::string>& arguments);

// Writes each capture to DIR/captures/NAME and breaks the broken ones: kMissingImage deletes
// img_007.png; kMalformedLp replaces the manifest by a .lp file whose line 5 has "abc" for a
// coordinate.
void WriteCaptures(const std::filesystem::path& dir, const std::vector<TestCapture>& captures);

// DIR/recipe.json: every capture of DIR/captures, fitted with gradient and ptm, with maps,
// .ptm, .rti, the viewer and the evaluation report, into DIR/out/NAME.
std::filesystem::path WriteTestRecipe(const std::filesystem::path& dir);

// WriteCaptures, WriteTestRecipe and `photomat batch plan` into DIR/batch, which it returns.
std::filesystem::path PlanTestCollection(const std::filesystem::path& dir,
                                         const std::vector<TestCapture>& captures);

// Runs, in `folder`, the photomat commands a person would type for one capture of that recipe.
// Returns "" or the first failing command's output.
std::string RunByHand(const std::filesystem::path& capture, const std::string& name,
                      const std::filesystem::path& folder);

// The files under `root`, relative, sorted; the batch's done record is left out.
std::vector<std::string> ListFiles(const std::filesystem::path& root);

// A file's bytes with the value of every EXR header's capDate attribute blanked: OpenImageIO
// stamps the wall-clock second of writing there (its "DateTime"), so two runs by hand differ in
// those 19 bytes.
std::string ReadComparableBytes(const std::filesystem::path& file);

// Expects the same files under both folders, byte for byte (ReadComparableBytes).
void ExpectSameOutputs(const std::filesystem::path& by_hand, const std::filesystem::path& batch);

// One capture of the recipe: run by hand into `by_hand`, then compared with the batch's `output`.
struct ByHandRun {
  std::filesystem::path capture;
  std::string name;
  std::filesystem::path by_hand;
  std::filesystem::path output;
};
// RunByHand for every run, two at a time (the machine's cores), then ExpectSameOutputs for each.
void ExpectSameAsByHand(const std::vector<ByHandRun>& runs);

// The attempts a task log records ("=== attempt N" lines).
int CountAttempts(const std::filesystem::path& log);

}  // namespace photomat::batch::testing
