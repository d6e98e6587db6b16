// Progress reporting for long work. Stages take a Progress& and call update() now and then; the
// CLI's terminal sink draws a bar with an ETA, a plain sink prints lines (CI logs), and any
// sink can ask the work to stop (Ctrl-C, or an engine's cancel button).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

namespace afterglow {

class Progress {
 public:
  virtual ~Progress() = default;
  // Starts a named stage of `total` work units.
  virtual void begin(const std::string& stage, size_t total);
  // Adds `done` units to the current stage; thread-safe.
  void advance(size_t done = 1);
  // Ends the current stage.
  virtual void end();

  void cancel() { cancelled_ = true; }
  bool cancelled() const { return cancelled_; }

 protected:
  virtual void draw(bool final) {}
  std::string stage_;
  size_t total_ = 0;
  std::atomic<size_t> done_{0};
  std::atomic<bool> cancelled_{false};
  std::chrono::steady_clock::time_point start_;
  std::atomic<int64_t> lastDrawMs_{0};
};

// Draws "stage [#####.....] 42% ETA 3s" on a terminal, or one line per stage otherwise.
class ConsoleProgress : public Progress {
 public:
  explicit ConsoleProgress(FILE* out = stderr, bool quiet = false);
  void begin(const std::string& stage, size_t total) override;
  void end() override;

 protected:
  void draw(bool final) override;

 private:
  FILE* out_;
  bool tty_;
  bool quiet_;
};

// A Progress that reports nothing (library default).
Progress& nullProgress();

}  // namespace afterglow
