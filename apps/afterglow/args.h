// Hand-written command-line parsing for the afterglow subcommands: options as `--name value`,
// `--name=value` or a short alias, flags without a value, options whose value may be left out,
// and positional arguments.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace afterglow::cli {

// Process exit codes (README and `afterglow --help` list them).
enum ExitCode : int {
  kExitOk = 0,
  kExitBadInput = 1,     // the scene could not be loaded or failed validation
  kExitUsage = 2,        // the command line is wrong
  kExitOutput = 3,       // an output file could not be written
  kExitInterrupted = 130 // Ctrl-C (128 + SIGINT)
};

struct OptionSpec {
  std::string name;       // long name without dashes, e.g. "texels-per-unit"
  char shortName = 0;     // e.g. 'o'; 0 = none
  bool takesValue = true; // false for flags such as --quiet
  // For an option whose value may be left out (`--probe-spheres [N|all]`): the next argument
  // is its value only when this accepts it; otherwise the option stands alone with value "".
  // (--name=value always gives the value.)
  bool (*optionalValue)(const std::string& next) = nullptr;
};

class Args {
 public:
  // Parses argv[first..argc). On failure returns false and sets error() to a one-line message.
  bool parse(int argc, char** argv, int first, const std::vector<OptionSpec>& specs);
  const std::string& error() const { return error_; }

  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::string get(const std::string& name, const std::string& fallback = "") const;  // the last
  // Every value a repeatable option was given, in command-line order.
  std::vector<std::string> getAll(const std::string& name) const;
  const std::vector<std::string>& positional() const { return positional_; }
  // The one positional argument (`what` names it in the error: "missing SCENE", "one SCENE
  // only, got 'b' too"); false with error() set when there is none or more than one.
  bool single(const std::string& what, std::string* out);

  // Typed getters: false (with error() set) when the value does not parse or is out of range.
  bool getInt(const std::string& name, int fallback, int minValue, int maxValue, int* out);
  bool getFloat(const std::string& name, float fallback, float minExclusive, float maxValue,
                float* out);

 private:
  std::map<std::string, std::string> values_;
  std::map<std::string, std::vector<std::string>> all_;
  std::vector<std::string> positional_;
  std::string error_;
};

}  // namespace afterglow::cli
