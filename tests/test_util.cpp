#include "test_util.hpp"

#include <atomic>
#include <random>

namespace tsm_test {

TempDir::TempDir() {
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  path = std::filesystem::temp_directory_path() /
         ("tsm-test-" + std::to_string(rd()) + "-" + std::to_string(counter++));
  std::filesystem::create_directories(path);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
}

}  // namespace tsm_test
