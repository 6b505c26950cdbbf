#include "core/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>

namespace photomat {
namespace {

std::string FormatSeconds(double seconds) {
  const auto s = static_cast<long>(std::max(0.0, seconds) + 0.5);
  return s >= 3600 ? fmt::format("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
                   : fmt::format("{:02}:{:02}", s / 60, s % 60);
}

}  // namespace

TerminalProgressBar::TerminalProgressBar(std::FILE* stream, bool force)
    : stream_(stream), enabled_(force || (stream && isatty(fileno(stream)))) {}

TerminalProgressBar::~TerminalProgressBar() {
  if (active_) Finish();
}

void TerminalProgressBar::Start(const std::string& label, std::size_t total) {
  if (active_) Finish();
  label_ = label;
  total_ = total;
  done_ = 0;
  active_ = true;
  start_ = last_draw_ = std::chrono::steady_clock::now();
  Draw(false);
}

void TerminalProgressBar::Advance(std::size_t steps) {
  done_ += steps;
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  std::unique_lock lock(draw_mutex_, std::try_to_lock);
  if (!lock.owns_lock() || now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  Draw(false);
}

void TerminalProgressBar::Finish() {
  if (!active_) return;
  std::lock_guard lock(draw_mutex_);
  Draw(true);
  active_ = false;
}

std::string TerminalProgressBar::Render() const {
  constexpr int kWidth = 30;
  const std::size_t done = std::min(done_.load(), total_);
  const double fraction = total_ == 0 ? 1.0 : static_cast<double>(done) / total_;
  const int filled = static_cast<int>(fraction * kWidth);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::string eta =
      done == 0 ? "--:--" : FormatSeconds(elapsed * (1.0 - fraction) / std::max(fraction, 1e-9));
  return fmt::format("{} [{}{}] {:3.0f}% {}/{} {} eta {}", label_, std::string(filled, '#'),
                     std::string(kWidth - filled, '.'), 100.0 * fraction, done, total_,
                     FormatSeconds(elapsed), eta);
}

void TerminalProgressBar::Draw(bool final_line) {
  if (!enabled_) return;
  std::fputs(("\r\033[K" + Render() + (final_line ? "\n" : "")).c_str(), stream_);
  std::fflush(stream_);
}

}  // namespace photomat
