// Where tests find data. Real data in ../shared/data is never copied into the
// repo; tests that need it skip with a message when it is absent.
#pragma once
#include <cstdlib>
#include <string>
#include <sys/stat.h>

namespace lk::test {

inline std::string source_dir() { return LK_SOURCE_DIR; }
// LK_SHARED_DATA=DIR overrides it (a git worktree elsewhere than beside ../shared).
inline std::string shared_data_dir() {
  const char* dir = std::getenv("LK_SHARED_DATA");
  return dir && *dir ? dir : LK_SOURCE_DIR "/../shared/data";
}
inline bool exists(const std::string& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0;
}
// A fresh scratch folder for a test's files (under the build tree).
std::string scratch_dir(const std::string& name);
// The whole file as bytes ("" when it cannot be read).
std::string read_file_text(const std::string& path);
// Runs `likeness <args>` from the build's bin folder, stdout discarded and
// stderr into stderr_path; returns its exit code (-1 if it did not exit).
int run_likeness(const std::string& args, const std::string& stderr_path = "/dev/null");

}  // namespace lk::test

// Use at the top of a TEST_CASE that needs ../shared/data/<rel>.
#define LK_REQUIRE_SHARED(rel)                                                      \
  do {                                                                              \
    if (!lk::test::exists(lk::test::shared_data_dir() + "/" + (rel))) {             \
      WARN("skipped: ../shared/data/" << (rel) << " is absent (real data is not in the repo)"); \
      return;                                                                       \
    }                                                                               \
  } while (0)

// Use at the top of a TEST_CASE that runs the `likeness` CLI (run_likeness):
// skips with a message when the harness is not built.
#define LK_REQUIRE_LIKENESS()                                                       \
  do {                                                                              \
    if (!lk::test::exists(std::string(LK_BIN_DIR) + "/likeness")) {                \
      WARN("skipped: " << LK_BIN_DIR << "/likeness is not built");                 \
      return;                                                                       \
    }                                                                               \
  } while (0)
