#include "test_util.hpp"

#include "tsm/tsm.hpp"

#include <atomic>
#include <cctype>
#include <cstdlib>
#include <random>

namespace tsm_test {

int refused_flips(const std::string& bytes, size_t stride, int mask, size_t from) {
  int refused = 0;
  for (size_t i = from; i < bytes.size(); i += stride) {
    std::string bad = bytes;
    bad[i] = static_cast<char>(bad[i] ^ mask);
    tsm::Mesh out;
    const tsm::Status s = tsm::decode(bad, out);
    if (!s.ok()) {
      EXPECT_FALSE(s.message().empty()) << "byte " << i;
      ++refused;
    } else {
      EXPECT_TRUE(out.valid()) << "byte " << i;
    }
  }
  return refused;
}

bool running_in_ci() {
  const char* ci = std::getenv("CI");
  if (ci == nullptr) return false;
  std::string v(ci);
  for (char& c : v) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return !v.empty() && v != "0" && v != "false";
}

std::string corpus_missing_message() {
  return "corpus not found at " + corpus_dir() +
         " (clone the project beside ../shared, or set TSM_CORPUS to the corpus folder)";
}

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
