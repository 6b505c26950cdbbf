#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>

namespace photomat {

// Progress of a long loop. Library code reports to this interface and never draws itself; the
// command-line tool passes a TerminalProgressBar. Implementations must be thread-safe: parallel
// loops call Advance() from several threads.
class Progress {
 public:
  virtual ~Progress() = default;
  // A new phase of `total` steps.
  virtual void Start(const std::string& label, std::size_t total) = 0;
  virtual void Advance(std::size_t steps = 1) = 0;
  // The phase is over (draws the final state).
  virtual void Finish() = 0;
};

// Reports nothing; what library functions use when given no Progress.
class NullProgress final : public Progress {
 public:
  void Start(const std::string&, std::size_t) override {}
  void Advance(std::size_t) override {}
  void Finish() override {}
};

// A one-line bar with percentage, counts, elapsed time and ETA on a stream, redrawn at most ten
// times a second. Draws only when the stream is a terminal (so logs and pipes stay clean), unless
// `force` is set.
class TerminalProgressBar final : public Progress {
 public:
  explicit TerminalProgressBar(std::FILE* stream = stderr, bool force = false);
  ~TerminalProgressBar() override;

  void Start(const std::string& label, std::size_t total) override;
  void Advance(std::size_t steps = 1) override;
  void Finish() override;

  bool enabled() const { return enabled_; }
  // The line that would be drawn now (for tests).
  std::string Render() const;

 private:
  void Draw(bool final_line);

  std::FILE* stream_;
  bool enabled_;
  std::string label_;
  std::size_t total_ = 0;
  std::atomic<std::size_t> done_{0};
  bool active_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  std::mutex draw_mutex_;
};

// Progress* or a NullProgress: lets functions take an optional Progress* argument.
inline Progress& OrNull(Progress* progress, NullProgress& fallback) {
  return progress ? *progress : fallback;
}

}  // namespace photomat
