// `tsm simplify`, `tsm compare` and `tsm encode --max-error`, run as a
// separate process (TSM_CLI_PATH): the bound holds end to end, as measured
// by `tsm compare`, and bad command lines are refused with the right code.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "mesh_gen.hpp"
#include "surface_gen.hpp"
#include "test_util.hpp"
#include "tsm/io.hpp"

namespace {

struct ToolRun {
  int code = -1;
  std::string out, err;
};

std::string slurp_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

class CliGeometry : public ::testing::Test {
 protected:
  ToolRun tsm(const std::string& args) {
    const std::string out = dir.file("stdout.txt"), err = dir.file("stderr.txt");
    const std::string cmd =
        std::string("'") + TSM_CLI_PATH + "' " + args + " >'" + out + "' 2>'" + err + "' </dev/null";
    const int status = std::system(cmd.c_str());
    ToolRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    r.out = slurp_file(out);
    r.err = slurp_file(err);
    return r;
  }
  std::string input() {
    const std::string path = dir.file("torus.ply");
    EXPECT_TRUE(tsm::write_mesh(path, tsm_test::torus(40, 20)).ok());
    return path;
  }
  nlohmann::json compare(const std::string& a, const std::string& b) {
    const ToolRun r = tsm("compare '" + a + "' '" + b + "' --json --samples 200000");
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(r.out);
  }
  tsm_test::TempDir dir;
};

TEST_F(CliGeometry, SimplifyStaysWithinTheBoundAsCompareMeasuresIt) {
  const std::string in = input(), out = dir.file("small.obj");
  const ToolRun r = tsm("simplify '" + in + "' -o '" + out + "' --max-error 0.5% --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json s = nlohmann::json::parse(r.out);
  EXPECT_LT(s["faces_out"].get<int>(), s["faces_in"].get<int>() / 2);
  EXPECT_DOUBLE_EQ(s["max_error_percent"].get<double>(), 0.5);
  const nlohmann::json c = compare(in, out);
  EXPECT_LE(c["hausdorff_percent"].get<double>(), 0.5);
  EXPECT_GT(c["hausdorff_percent"].get<double>(), 0.1);
  EXPECT_EQ(c["triangles_b"].get<int>(), s["faces_out"].get<int>());
  // An existing output is not replaced without -f.
  EXPECT_EQ(tsm("simplify '" + in + "' -o '" + out + "' --max-error 0.5%").code, 4);
}

TEST_F(CliGeometry, EncodeWithMaxErrorKeepsTheDecodedMeshWithinIt) {
  const std::string in = input(), out = dir.file("small.tsm");
  const ToolRun r = tsm("encode '" + in + "' -o '" + out + "' --max-error 0.5% -q 12");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json c = compare(in, out);
  EXPECT_LE(c["hausdorff_percent"].get<double>(), 0.5);
  EXPECT_LT(c["triangles_b"].get<int>(), 1600);
}

TEST_F(CliGeometry, RefusesBadCommandLines) {
  const std::string in = input();
  ToolRun r = tsm("simplify '" + in + "' -o '" + dir.file("x.ply") + "' --max-error 0.5x");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--max-error 0.5x"), std::string::npos) << r.err;
  r = tsm("simplify '" + in + "' -o '" + dir.file("x.ply") + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--max-error"), std::string::npos) << r.err;
  r = tsm("encode '" + in + "' -o '" + dir.file("x.tsm") + "' --max-error -1");
  EXPECT_EQ(r.code, 2);
  r = tsm("compare '" + in + "' '" + dir.file("missing.ply") + "'");
  EXPECT_EQ(r.code, 4);
  EXPECT_NE(r.err.find("missing.ply"), std::string::npos) << r.err;
}

}  // namespace
