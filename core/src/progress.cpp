#include "afterglow/core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace afterglow {

namespace {
int64_t msSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t)
      .count();
}
}  // namespace

void Progress::begin(const std::string& stage, size_t total) {
  stage_ = stage;
  total_ = total;
  done_ = 0;
  lastDrawMs_ = 0;
  start_ = std::chrono::steady_clock::now();
  draw(false);
}

void Progress::advance(size_t done) {
  done_ += done;
  // Redraw at most ten times a second, from whichever thread gets there first.
  int64_t now = msSince(start_);
  int64_t last = lastDrawMs_.load();
  if (now - last >= 100 && lastDrawMs_.compare_exchange_strong(last, now)) draw(false);
}

void Progress::end() { draw(true); }

ConsoleProgress::ConsoleProgress(FILE* out, bool quiet)
    : out_(out), tty_(isatty(fileno(out)) != 0), quiet_(quiet) {}

void ConsoleProgress::begin(const std::string& stage, size_t total) { Progress::begin(stage, total); }

void ConsoleProgress::end() { Progress::end(); }

void ConsoleProgress::draw(bool final) {
  if (quiet_) return;
  double seconds = msSince(start_) / 1000.0;
  size_t done = std::min(done_.load(), total_);
  double fraction = total_ ? double(done) / double(total_) : 1.0;
  if (!tty_) {
    // Plain logs get one line per stage, when it ends.
    if (final) std::fprintf(out_, "%s: done in %.2f s\n", stage_.c_str(), seconds);
    return;
  }
  constexpr int kWidth = 30;
  int filled = int(std::lround(fraction * kWidth));
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = '\0';
  if (final) {
    std::fprintf(out_, "\r%-24s [%s] 100%%  %.2f s      \n", stage_.c_str(), bar, seconds);
  } else {
    double eta = fraction > 0.01 ? seconds * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(out_, "\r%-24s [%s] %3d%%  ETA %.0f s   ", stage_.c_str(), bar,
                 int(fraction * 100.0), eta);
  }
  std::fflush(out_);
}

Progress& nullProgress() {
  static thread_local Progress progress;
  return progress;
}

}  // namespace afterglow
