#include "test_data.h"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace lk::test {

std::string scratch_dir(const std::string& name) {
  const std::string dir = std::string(LK_BINARY_DIR) + "/test_scratch/" + name;
  const std::string cmd = "mkdir -p '" + dir + "'";
  if (std::system(cmd.c_str()) != 0) return "/tmp";
  return dir;
}

std::string read_file_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

int run_likeness(const std::string& args, const std::string& stderr_path) {
  const std::string cmd = std::string(LK_BIN_DIR) + "/likeness " + args + " > /dev/null 2> " + stderr_path;
  const int r = std::system(cmd.c_str());
  return WIFEXITED(r) ? WEXITSTATUS(r) : -1;
}

}  // namespace lk::test
