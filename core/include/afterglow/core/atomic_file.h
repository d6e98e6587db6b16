// Atomic output: every file afterglow writes goes to a temporary name beside its destination and
// is renamed into place only when the whole job has succeeded, so a failed or interrupted run
// leaves no half-written output.
#pragma once

#include <string>
#include <vector>

#include "afterglow/core/status.h"

namespace afterglow {

// Collects the files of one job. tempPath() hands out a temporary path to write to; commit()
// renames them all into place; the destructor deletes whatever was not committed.
class AtomicOutput {
 public:
  AtomicOutput() = default;
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  ~AtomicOutput();

  // Returns the temporary path to write `finalPath` to. Creates missing parent folders.
  std::string tempPath(const std::string& finalPath);
  // Writes bytes to the temporary file for finalPath.
  Status write(const std::string& finalPath, const std::string& bytes);
  // Renames every temporary file onto its final path.
  Status commit();
  // Deletes every temporary file (also done by the destructor).
  void abort();

 private:
  struct Entry {
    std::string temp, final;
  };
  std::vector<Entry> entries_;
  bool committed_ = false;
};

// Reads a whole file; the error names the path.
Result<std::string> readFile(const std::string& path);

}  // namespace afterglow
