#include "args.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "afterglow/core/status.h"

namespace afterglow::cli {

bool Args::parse(int argc, char** argv, int first, const std::vector<OptionSpec>& specs) {
  bool onlyPositional = false;  // after "--" everything is positional
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (onlyPositional || arg.size() < 2 || arg[0] != '-') {
      positional_.push_back(arg);
      continue;
    }
    if (arg == "--") {
      onlyPositional = true;
      continue;
    }
    const OptionSpec* spec = nullptr;
    std::string value;
    bool inlineValue = false;
    if (arg[1] == '-') {
      std::string name = arg.substr(2);
      size_t eq = name.find('=');
      if (eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        inlineValue = true;
      }
      for (const OptionSpec& s : specs)
        if (s.name == name) spec = &s;
    } else if (arg.size() == 2) {
      for (const OptionSpec& s : specs)
        if (s.shortName != 0 && s.shortName == arg[1]) spec = &s;
    }
    if (!spec) {
      error_ = format("unknown option '%s'", arg.c_str());
      return false;
    }
    if (!spec->takesValue) {
      if (inlineValue) {
        error_ = format("option '--%s' takes no value", spec->name.c_str());
        return false;
      }
      values_[spec->name] = "1";
      continue;
    }
    if (!inlineValue && spec->optionalValue) {
      if (i + 1 < argc && spec->optionalValue(argv[i + 1])) value = argv[++i];
    } else if (!inlineValue) {
      if (i + 1 >= argc) {
        error_ = format("option '%s' needs a value", arg.c_str());
        return false;
      }
      value = argv[++i];
    }
    values_[spec->name] = value;
    all_[spec->name].push_back(value);
  }
  return true;
}

std::vector<std::string> Args::getAll(const std::string& name) const {
  auto it = all_.find(name);
  return it == all_.end() ? std::vector<std::string>() : it->second;
}

std::string Args::get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

bool Args::getInt(const std::string& name, int fallback, int minValue, int maxValue, int* out) {
  if (!has(name)) {
    *out = fallback;
    return true;
  }
  const std::string& text = values_[name];
  char* end = nullptr;
  errno = 0;
  long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < minValue || v > maxValue) {
    error_ = format("--%s wants a whole number from %d to %d, got '%s'", name.c_str(), minValue,
                    maxValue, text.c_str());
    return false;
  }
  *out = int(v);
  return true;
}

bool Args::getFloat(const std::string& name, float fallback, float minExclusive, float maxValue,
                    float* out) {
  if (!has(name)) {
    *out = fallback;
    return true;
  }
  const std::string& text = values_[name];
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno != 0 || !std::isfinite(v) || v <= minExclusive ||
      v > maxValue) {
    error_ = format("--%s wants a number above %g and at most %g, got '%s'", name.c_str(),
                    double(minExclusive), double(maxValue), text.c_str());
    return false;
  }
  *out = float(v);
  return true;
}

bool Args::single(const std::string& what, std::string* out) {
  if (positional_.empty()) {
    error_ = "missing " + what;
    return false;
  }
  if (positional_.size() > 1) {
    error_ = "one " + what + " only, got '" + positional_[1] + "' too";
    return false;
  }
  *out = positional_[0];
  return true;
}

}  // namespace afterglow::cli
