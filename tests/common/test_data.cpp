#include "test_data.h"

#include <cstdlib>
#include <string>

namespace lk::test {

std::string scratch_dir(const std::string& name) {
  const std::string dir = std::string(LK_BINARY_DIR) + "/test_scratch/" + name;
  const std::string cmd = "mkdir -p '" + dir + "'";
  if (std::system(cmd.c_str()) != 0) return "/tmp";
  return dir;
}

}  // namespace lk::test
