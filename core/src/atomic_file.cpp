#include "afterglow/core/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace afterglow {

AtomicOutput::~AtomicOutput() { abort(); }

std::string AtomicOutput::tempPath(const std::string& finalPath) {
  fs::path p(finalPath);
  std::error_code ec;
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  // Dot-prefixed and tagged with the pid so a crashed run's leftovers are recognisable.
  std::string temp = (p.parent_path() / ("." + p.filename().string() + ".tmp" +
                                         std::to_string(::getpid())))
                         .string();
  entries_.push_back({temp, finalPath});
  return temp;
}

Status AtomicOutput::write(const std::string& finalPath, const std::string& bytes) {
  std::string temp = tempPath(finalPath);
  std::ofstream out(temp, std::ios::binary);
  if (!out) return Status::error(format("%s: cannot open for writing", finalPath.c_str()));
  out.write(bytes.data(), std::streamsize(bytes.size()));
  out.close();
  if (!out) return Status::error(format("%s: write failed (disk full?)", finalPath.c_str()));
  return Status::ok();
}

Status AtomicOutput::commit() {
  for (const Entry& e : entries_) {
    std::error_code ec;
    fs::rename(e.temp, e.final, ec);
    if (ec)
      return Status::error(format("%s: cannot move into place: %s", e.final.c_str(),
                                  ec.message().c_str()));
  }
  committed_ = true;
  entries_.clear();
  return Status::ok();
}

void AtomicOutput::abort() {
  for (const Entry& e : entries_) {
    std::error_code ec;
    fs::remove(e.temp, ec);
  }
  entries_.clear();
}

Result<std::string> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Result<std::string>::error(format("%s: cannot open file", path.c_str()));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return Result<std::string>::error(format("%s: read error", path.c_str()));
  return ss.str();
}

}  // namespace afterglow
