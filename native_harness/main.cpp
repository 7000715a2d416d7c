// likeness: the native command-line harness.
#include "command.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <cstdlib>
#include <iostream>

namespace lk::cli {

std::map<std::string, Command>& registry() {
  static std::map<std::string, Command> r;
  return r;
}

std::vector<std::string> split_list(const std::string& s, char sep) {
  std::vector<std::string> out;
  size_t a = 0;
  while (a < s.size()) {
    const size_t b = std::min(s.find(sep, a), s.size());
    if (b > a) out.push_back(s.substr(a, b - a));
    a = b + 1;
  }
  return out;
}

std::string Args::get(const std::string& key, const std::string& def) const {
  auto it = options.find(key);
  return (it == options.end() || it->second.empty()) ? def : it->second.front();
}

std::vector<std::string> Args::get_all(const std::string& key) const {
  auto it = options.find(key);
  return it == options.end() ? std::vector<std::string>{} : it->second;
}

namespace {

std::string range_text(double lo, double hi, bool integer) {
  auto num = [&](double v) {
    if (integer) return std::to_string(static_cast<long long>(v));
    std::ostringstream o;
    o << v;
    return o.str();
  };
  if (lo <= -DBL_MAX / 2 || (integer && lo <= INT_MIN)) return hi >= DBL_MAX / 2 || (integer && hi >= INT_MAX) ? "" : " <= " + num(hi);
  if (hi >= DBL_MAX / 2 || (integer && hi >= INT_MAX)) return " >= " + num(lo);
  return " in " + num(lo) + ".." + num(hi);
}

bool refuse(const std::string& key, const char* what, double lo, double hi, const std::string& value) {
  std::cerr << "error: --" << key << " takes " << what << range_text(lo, hi, std::string(what) == "an integer")
            << ", got '" << value << "'\n";
  return false;
}

}  // namespace

bool Args::get_int(const std::string& key, int def, int& out, int lo, int hi) const {
  out = def;
  if (!has(key)) return true;
  const std::string v = get(key);
  char* end = nullptr;
  errno = 0;
  const long long x = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno == ERANGE || x < lo || x > hi) return refuse(key, "an integer", lo, hi, v);
  out = static_cast<int>(x);
  return true;
}

bool Args::get_double(const std::string& key, double def, double& out, double lo, double hi) const {
  out = def;
  if (!has(key)) return true;
  const std::string v = get(key);
  char* end = nullptr;
  errno = 0;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(x) || x < lo || x > hi)
    return refuse(key, "a number", lo, hi, v);
  out = x;
  return true;
}

Args parse_args(int argc, char** argv, int first) {
  Args a;
  std::string key;
  for (int i = first; i < argc; ++i) {
    std::string s = argv[i];
    if (s.size() > 2 && s.rfind("--", 0) == 0) {
      key = s.substr(2);
      a.options[key];  // a flag with no value is still present
    } else if (!key.empty()) {
      a.options[key].push_back(s);
    } else {
      a.positional.push_back(s);
    }
  }
  return a;
}

int fail(const std::string& command, const std::string& message) {
  std::cerr << "likeness " << command << ": error: " << message << "\n";
  return 1;
}

bool only_known_options(const std::string& command, const Args& args, std::initializer_list<const char*> known,
                        size_t max_positional) {
  if (args.positional.size() > max_positional) {
    fail(command, "unexpected argument '" + args.positional[max_positional] +
                      "' (options are --name value; see `likeness help`)");
    return false;
  }
  for (const auto& [key, values] : args.options) {
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (!ok) {
      fail(command, "unknown option --" + key + " (see `likeness help`)");
      return false;
    }
  }
  return true;
}

}  // namespace lk::cli

static void usage() {
  std::cout << "likeness: scan + photos -> animatable, textured, multiresolution head\n\n"
               "commands:\n";
  for (auto& [name, c] : lk::cli::registry())
    std::cout << "  " << c.usage << "\n      " << c.summary << "\n";
}

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "help") {
    usage();
    return argc < 2 ? 2 : 0;
  }
  auto& r = lk::cli::registry();
  auto it = r.find(argv[1]);
  if (it == r.end()) {
    std::cerr << "likeness: unknown command '" << argv[1] << "'\n\n";
    usage();
    return 2;
  }
  lk::cli::Args args = lk::cli::parse_args(argc, argv, 2);
  if (args.has("help")) {
    std::cout << it->second.usage << "\n  " << it->second.summary << "\n";
    if (it->second.details) std::cout << it->second.details();
    return 0;
  }
  return it->second.run(args);
}
