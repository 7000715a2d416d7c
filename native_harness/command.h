// The likeness command-line harness: each command lives in its own cmd_*.cpp
// and registers itself with a static Registrar. Commands are thin shells:
// read files, call core/, write files, print.
#pragma once
#include <cfloat>
#include <cstddef>
#include <climits>
#include <functional>
#include <initializer_list>
#include <map>
#include <string>
#include <vector>

namespace lk::cli {

// Parsed "--key value" / "--flag" arguments; positional arguments in order.
struct Args {
  std::map<std::string, std::vector<std::string>> options;  // --key v1 v2 ...
  std::vector<std::string> positional;

  bool has(const std::string& key) const { return options.count(key) != 0; }
  std::string get(const std::string& key, const std::string& def = "") const;
  std::vector<std::string> get_all(const std::string& key) const;
  // Returns false (and prints "--key takes an integer in lo..hi, got 'v'")
  // when the value is missing, not a number, not finite or outside [lo, hi];
  // values are never wrapped or clamped (--size 4294967312 is refused).
  bool get_int(const std::string& key, int def, int& out, int lo = INT_MIN, int hi = INT_MAX) const;
  bool get_double(const std::string& key, double def, double& out, double lo = -DBL_MAX,
                  double hi = DBL_MAX) const;
};

// "a,b,,c" -> {"a", "b", "c"}: a comma-separated (or sep-separated) option
// value's items, empty ones left out.
std::vector<std::string> split_list(const std::string& s, char sep = ',');

Args parse_args(int argc, char** argv, int first);

struct Command {
  std::string name;
  std::string usage;    // one line: "likeness render --mesh FILE ..."
  std::string summary;  // what it does
  std::function<int(const Args&)> run;  // exit code: 0 ok, 1 failed, 2 usage
  std::function<std::string()> details;  // optional: more lines for `likeness <command> --help`
};

std::map<std::string, Command>& registry();

struct Registrar {
  explicit Registrar(Command c) { registry()[c.name] = std::move(c); }
};

// Prints "likeness <command>: error: <message>" to stderr and returns 1.
int fail(const std::string& command, const std::string& message);

// False (after printing "unknown option --key (see `likeness help`)" through
// fail) when args has an option not in known, or more than max_positional
// positional words; commands then exit with 2.
bool only_known_options(const std::string& command, const Args& args, std::initializer_list<const char*> known,
                        size_t max_positional = 0);

}  // namespace lk::cli

namespace lk::cli {

// `likeness bench` runs every registered benchmark section in name order
// (or only those named with --only). Each prints its own table with the
// papers' figures beside ours. Benchmarks are measurements, never tests.
struct Bench {
  std::string name;
  std::string summary;
  std::function<int(const Args&)> run;  // 0 ok
};
std::map<std::string, Bench>& bench_registry();
struct BenchRegistrar {
  explicit BenchRegistrar(Bench b) { bench_registry()[b.name] = std::move(b); }
};

}  // namespace lk::cli
