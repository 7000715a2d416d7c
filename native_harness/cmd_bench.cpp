// likeness bench: runs the registered benchmark sections.
#include "command.h"

#include <iostream>
#include <set>

namespace lk::cli {

std::map<std::string, Bench>& bench_registry() {
  static std::map<std::string, Bench> r;
  return r;
}

namespace {

int run_bench(const Args& args) {
  const auto only_list = args.get_all("only");
  std::set<std::string> only(only_list.begin(), only_list.end());
  int failures = 0, ran = 0;
  for (auto& [name, b] : bench_registry()) {
    if (!only.empty() && !only.count(name)) continue;
    std::cout << "\n== " << name << ": " << b.summary << "\n";
    ++ran;
    if (b.run(args) != 0) {
      std::cout << "   (section " << name << " failed)\n";
      ++failures;
    }
  }
  if (ran == 0) {
    std::cerr << "likeness bench: no section matched; sections:";
    for (auto& [name, b] : bench_registry()) std::cerr << " " << name;
    std::cerr << "\n";
    return 2;
  }
  return failures ? 1 : 0;
}

std::string sections() {
  std::string out = "sections (all by default; --only picks some):\n";
  for (auto& [name, b] : bench_registry()) {
    const std::string pad(name.size() < 10 ? 10 - name.size() : 1, ' ');
    out += "  " + name + pad + b.summary + "\n";
  }
  return out;
}

Registrar reg({"bench", "likeness bench [--only SECTION ...] [--quick]",
               "measures speed and accuracy, printed beside the papers' figures", run_bench, sections});

}  // namespace
}  // namespace lk::cli
