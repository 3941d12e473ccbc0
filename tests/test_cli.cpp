// The `tsm` command-line tool, run as a separate process (TSM_CLI_PATH):
// every command, exit codes, messages, and the promises about files (never
// overwrite the input, never clobber without -f, never leave partial output).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/tsm.hpp"

namespace {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string out, err;
};

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

void spit(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary);
  f << bytes;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::is_regular_file(TSM_CLI_PATH)) << "the tsm tool is not built at " << TSM_CLI_PATH;
  }

  // Runs `tsm <args>` with stdout and stderr captured in files of the temp dir
  // (kept outside the folder the tests inspect for leftovers).
  Result tsm(const std::string& args) {
    const std::string out = logs.file("stdout"), err = logs.file("stderr");
    const std::string cmd = quote(TSM_CLI_PATH) + " " + args + " >" + quote(out) + " 2>" + quote(err) + " </dev/null";
    int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }

  std::string file(const std::string& name) const { return dir.file(name); }
  std::string q(const std::string& name) const { return quote(dir.file(name)); }

  // A small mesh written as binary PLY: in.ply.
  tsm::Mesh write_input(const std::string& name = "in.ply") {
    tsm::Mesh m = tsm_test::icosphere(2);
    tsm::Status s = tsm::write_mesh(file(name), m);
    EXPECT_TRUE(s.ok()) << s.to_string();
    return m;
  }

  // Files in the work folder whose name contains ".tmp-".
  int temporaries() const {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir.path))
      if (e.path().filename().string().find(".tmp-") != std::string::npos) ++n;
    return n;
  }

  tsm_test::TempDir dir, logs;
};

TEST_F(Cli, Version) {
  Result r = tsm("--version");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(std::string("tsm ") + tsm::version_string()), std::string::npos) << r.out;
}

TEST_F(Cli, HelpForEveryCommand) {
  Result r = tsm("--help");
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* cmd : {"encode", "decode", "info", "bench"}) EXPECT_NE(r.out.find(cmd), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Exit codes"), std::string::npos) << r.out;

  struct Expect {
    const char* cmd;
    const char* option;
  };
  for (const Expect& e : {Expect{"encode", "--quantization"}, Expect{"decode", "--max-vertices"},
                          Expect{"info", "--json"}, Expect{"bench", "--runs"}}) {
    r = tsm(std::string(e.cmd) + " --help");
    EXPECT_EQ(r.code, 0) << e.cmd << ": " << r.err;
    EXPECT_NE(r.out.find(e.option), std::string::npos) << e.cmd << ": " << r.out;
    EXPECT_NE(r.out.find("Example"), std::string::npos) << e.cmd << ": " << r.out;
  }
}

TEST_F(Cli, EncodeDecodeInfo) {
  tsm::Mesh m = write_input();
  Result r = tsm("encode " + q("in.ply") + " -o " + q("out.tsm") + " -q 12 -l 4");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("162 vertices"), std::string::npos) << r.out;
  std::string bytes = slurp(file("out.tsm"));
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
  EXPECT_EQ(fi.quantization_bits, 12);
  EXPECT_EQ(fi.level, 4);

  // Decode to PLY and to OBJ, both give the mesh back.
  r = tsm("decode " + q("out.tsm") + " -o " + q("back.ply"));
  ASSERT_EQ(r.code, 0) << r.err;
  r = tsm("decode " + q("out.tsm") + " -o " + q("back.obj") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  for (const char* name : {"back.ply", "back.obj"}) {
    tsm::Mesh back;
    tsm::Status s = tsm::read_mesh(file(name), back);
    ASSERT_TRUE(s.ok()) << name << ": " << s.to_string();
    auto c = tsm::compare_meshes(m, back, 12);
    EXPECT_TRUE(c.equal) << name << ": " << c.difference;
  }
  r = tsm("decode " + q("out.tsm") + " -o " + q("ascii.ply") + " --ascii --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(file("ascii.ply")).find("format ascii"), std::string::npos);

  r = tsm("info " + q("out.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("vertices 162"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("faces 320"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("quantization 12 bits"), std::string::npos) << r.out;

  r = tsm("info " + q("out.tsm") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.front(), '{');
  EXPECT_EQ(r.out.substr(r.out.size() - 2), "}\n");
  EXPECT_NE(r.out.find("\"vertices\": 162"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"faces\": 320"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"quantization_bits\": 12"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"bytes\": " + std::to_string(bytes.size())), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"sections\": [{"), std::string::npos) << r.out;
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Cli, DefaultOutputNamesAndOverwriteRules) {
  write_input();
  Result r = tsm("encode " + q("in.ply") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(file("in.tsm")));
  const std::string original_ply = slurp(file("in.ply"));

  // The default decode output is in.ply, which exists: refused without -f.
  r = tsm("decode " + q("in.tsm"));
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("-f"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(file("in.ply")), original_ply);
  // With -f it is replaced.
  r = tsm("decode " + q("in.tsm") + " -f --ascii --quiet");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(file("in.ply")), original_ply);

  // Encode does not clobber an existing mesh file without -f...
  spit(file("other.obj"), "v 0 0 0\n");
  r = tsm("encode " + q("in.ply") + " -o " + q("other.obj"));
  EXPECT_EQ(r.code, 3);
  EXPECT_EQ(slurp(file("other.obj")), "v 0 0 0\n");
  // ...but a previous .tsm is simply replaced.
  r = tsm("encode " + q("in.ply") + " -q 6 --quiet");
  EXPECT_EQ(r.code, 0) << r.err;
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(slurp(file("in.tsm")), fi).ok());
  EXPECT_EQ(fi.quantization_bits, 6);
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Cli, RefusesToOverwriteTheInput) {
  write_input();
  const std::string before = slurp(file("in.ply"));
  for (const char* force : {"", " -f"}) {
    Result r = tsm("encode " + q("in.ply") + " -o " + q("in.ply") + force);
    EXPECT_EQ(r.code, 3) << force;
    EXPECT_NE(r.err.find("overwrite the input"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(file("in.ply")), before);
    // The same file under another name.
    r = tsm("encode " + q("in.ply") + " -o " + quote(dir.path.string() + "/./in.ply") + force);
    EXPECT_EQ(r.code, 3) << force;
    EXPECT_EQ(slurp(file("in.ply")), before);
  }
  // decode: a .tsm file that happens to be named .ply, decoded onto itself.
  ASSERT_EQ(tsm("encode " + q("in.ply") + " -o " + q("packed.tsm") + " --quiet").code, 0);
  fs::copy_file(file("packed.tsm"), file("packed.ply"));
  const std::string packed = slurp(file("packed.ply"));
  Result r = tsm("decode " + q("packed.ply") + " -o " + q("packed.ply") + " -f");
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("overwrite the input"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(file("packed.ply")), packed);
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Cli, BadArgumentsExitTwo) {
  write_input();
  for (const std::string& args : std::vector<std::string>{std::string(""), std::string("frobnicate"), "encode " + q("in.ply") + " -q 31",
        "encode " + q("in.ply") + " -q 0", "encode " + q("in.ply") + " -l 10", "encode " + q("in.ply") + " -q x",
        "encode " + q("in.ply") + " --no-such-flag", "encode", "decode", "info",
        "encode " + q("in.ply") + " " + q("extra.ply"), "bench " + q("in.ply") + " --runs 0",
        "bench " + q("in.ply") + " -q 40", "decode " + q("in.ply") + " --max-vertices x"}) {
    Result r = tsm(args);
    EXPECT_EQ(r.code, 2) << "tsm " << args << "\n" << r.out << r.err;
    EXPECT_FALSE(r.err.empty() && r.out.empty()) << "tsm " << args << ": says nothing";
  }
  EXPECT_FALSE(fs::exists(file("in.tsm")));
}

TEST_F(Cli, NegativeLimitIsABadArgument) {
  // A negative limit must not silently become "no limit".
  write_input();
  ASSERT_EQ(tsm("encode " + q("in.ply") + " -o " + q("in.tsm") + " --quiet").code, 0);
  for (const char* opt : {"--max-vertices", "--max-faces"}) {
    Result r = tsm("decode " + q("in.tsm") + " -o " + q("out.ply") + " " + opt + " -5");
    EXPECT_EQ(r.code, 2) << opt << ": " << r.out << r.err;
    EXPECT_FALSE(fs::exists(file("out.ply"))) << opt;
    fs::remove(file("out.ply"));
  }
}

TEST_F(Cli, MissingInputExitTwo) {
  for (const char* cmd : {"encode", "decode", "info"}) {
    Result r = tsm(std::string(cmd) + " " + q("missing.file"));
    EXPECT_EQ(r.code, 2) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find("missing.file"), std::string::npos) << cmd << ": " << r.err;
  }
  EXPECT_EQ(temporaries(), 0);
  EXPECT_TRUE(fs::is_empty(dir.path));
}

TEST_F(Cli, CorruptInputExitThreeNamesTheFile) {
  write_input();
  ASSERT_EQ(tsm("encode " + q("in.ply") + " -o " + q("good.tsm") + " --quiet").code, 0);
  const std::string good = slurp(file("good.tsm"));

  spit(file("junk.tsm"), "this is not a tsm file at all");
  std::string damaged = good;
  damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x10);
  spit(file("damaged.tsm"), damaged);
  spit(file("short.tsm"), good.substr(0, good.size() - 3));

  for (const char* name : {"junk.tsm", "damaged.tsm", "short.tsm"}) {
    Result r = tsm("decode " + q(name) + " -o " + q("out.ply"));
    EXPECT_EQ(r.code, 3) << name << ": " << r.err;
    EXPECT_NE(r.err.find(name), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("error"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(file("out.ply"))) << name << ": partial output left behind";
    r = tsm("info " + q(name));
    EXPECT_EQ(r.code, 3) << name;
    EXPECT_NE(r.err.find(name), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << name;
  }
  // Over a caller's limit: refused, nothing written.
  Result r = tsm("decode " + q("good.tsm") + " -o " + q("out.obj") + " --max-vertices 10");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("limit"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file("out.obj")));
  // Decode refuses an output format it cannot write.
  r = tsm("decode " + q("good.tsm") + " -o " + q("out.stl"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_FALSE(fs::exists(file("out.stl")));
  // A malformed mesh file given to encode.
  spit(file("bad.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n");
  r = tsm("encode " + q("bad.ply") + " -o " + q("bad.tsm"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("bad.ply"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file("bad.tsm")));
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Cli, BenchOnASmallMesh) {
  write_input("small.ply");
  Result r = tsm("bench " + q("small.ply") + " --runs 1 -q 8 --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("| small.ply | 162 | 8 |"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("NOT exact"), std::string::npos) << r.out;
  EXPECT_EQ(r.err, "");

  r = tsm("bench " + q("small.ply") + " --runs 1 -q 8 --json --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("\"tsm_exact\": true"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"failures\": 0"), std::string::npos) << r.out;

  // A file it cannot read is a failure, reported, with exit code 3.
  spit(file("bad.ply"), "ply\nbroken");
  r = tsm("bench " + q("bad.ply") + " --runs 1 -q 8 --quiet");
  EXPECT_EQ(r.code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("bad.ply"), std::string::npos) << r.err;
}

}  // namespace
