// The `tsm` command-line tool, run as a separate process (TSM_CLI_PATH):
// every command, exit codes, messages, and the promises about files (never
// overwrite the input, never clobber without -f, never leave partial output).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/tsm.hpp"
#include "tsm/io.hpp"

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
  Result tsm(const std::string& args) { return sh("$TSM " + args + " </dev/null"); }

  // Runs a shell command line in which $TSM is the tool, with stdout and
  // stderr captured (unless the line redirects them itself).
  Result sh(const std::string& line) {
    const std::string out = logs.file("stdout"), err = logs.file("stderr");
    fs::remove(out);
    fs::remove(err);
    const std::string cmd = "TSM=" + quote(TSM_CLI_PATH) + "; { " + line + " ; } >" + quote(out) + " 2>" + quote(err);
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
  EXPECT_EQ(fi.format_version, 12u);  // one format until 1.0
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

  // Encode does not clobber an existing mesh file (its name is refused
  // before anything: encode writes .tsm) or any other file without -f...
  spit(file("other.obj"), "v 0 0 0\n");
  r = tsm("encode " + q("in.ply") + " -o " + q("other.obj"));
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(slurp(file("other.obj")), "v 0 0 0\n");
  spit(file("other.dat"), "data");
  r = tsm("encode " + q("in.ply") + " -o " + q("other.dat"));
  EXPECT_EQ(r.code, 3);
  EXPECT_EQ(slurp(file("other.dat")), "data");
  // ...nor a previous .tsm (it may be the only copy left): -f replaces it.
  const std::string previous = slurp(file("in.tsm"));
  r = tsm("encode " + q("in.ply") + " -q 6 --quiet");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("in.tsm: already exists; pass -f"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(file("in.tsm")), previous);
  r = tsm("encode " + q("in.ply") + " -q 6 --quiet -f");
  EXPECT_EQ(r.code, 0) << r.err;
  tsm::FileInfo fi;
  ASSERT_TRUE(tsm::inspect(slurp(file("in.tsm")), fi).ok());
  EXPECT_EQ(fi.quantization_bits, 6);
  EXPECT_EQ(temporaries(), 0);
}

TEST_F(Cli, RefusesToOverwriteTheInput) {
  write_input();
  const std::string before = slurp(file("in.ply"));
  // A PLY under a name that says nothing of its format, so that only the
  // rule about inputs stops the write (encode refuses .ply output names).
  fs::copy_file(file("in.ply"), file("in.dat"));
  for (const char* force : {"", " -f"}) {
    Result r = tsm("encode " + q("in.dat") + " -o " + q("in.dat") + force);
    EXPECT_EQ(r.code, 3) << force;
    EXPECT_NE(r.err.find("overwrite the input"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(file("in.dat")), before);
    // The same file under another name.
    r = tsm("encode " + q("in.dat") + " -o " + quote(dir.path.string() + "/./in.dat") + force);
    EXPECT_EQ(r.code, 3) << force;
    EXPECT_EQ(slurp(file("in.dat")), before);
    r = tsm("encode " + q("in.ply") + " -o " + q("in.ply") + force);
    EXPECT_NE(r.code, 0) << force;
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
        "bench " + q("in.ply") + " --runs 0",
        "bench " + q("in.ply") + " -q 40", "decode " + q("in.ply") + " --max-vertices x",
        "encode " + q("in.ply") + " --format-version 11"}) {  // one format: no such option
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

// A missing input is a file that cannot be read (exit code 4), reported by
// name like any other failed input, not a command-line error.
TEST_F(Cli, MissingInputIsAFailedInput) {
  for (const char* cmd : {"encode", "decode", "info"}) {
    Result r = tsm(std::string(cmd) + " " + q("missing.file"));
    EXPECT_EQ(r.code, 4) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find("missing.file: no such file; check the name"), std::string::npos) << cmd << ": " << r.err;
    EXPECT_EQ(r.err.find("File does not exist"), std::string::npos) << cmd << ": " << r.err;
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
  // Decode refuses an output name that does not say a format it writes.
  r = tsm("decode " + q("good.tsm") + " -o " + q("out.xyz"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_FALSE(fs::exists(file("out.xyz")));
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
  EXPECT_NE(r.out.find("tsm on one thread against Draco"), std::string::npos) << r.out;
  EXPECT_EQ(r.err, "");

  r = tsm("bench " + q("small.ply") + " --runs 1 -q 8 --json --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("\"tsm_exact\": true"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"failures\": 0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"threads\": 1"), std::string::npos) << r.out;
  // A closed manifold mesh: Draco's round trip is exact on Draco's own grid.
  if (r.out.find("\"draco\": true") != std::string::npos) {
    EXPECT_NE(r.out.find("\"draco_cl10_exact\": true"), std::string::npos) << r.out;
  }

  // A file it cannot read is a failure, reported, with exit code 3.
  spit(file("bad.ply"), "ply\nbroken");
  r = tsm("bench " + q("bad.ply") + " --runs 1 -q 8 --quiet");
  EXPECT_EQ(r.code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("bad.ply"), std::string::npos) << r.err;
}

// The simplification table: tsm within each bound it was given, and
// meshoptimizer (required in CI) within it too by the same measurement.
TEST_F(Cli, BenchSimplifiesBesideMeshoptimizer) {
  write_input("small.ply");
  Result r = tsm("bench " + q("small.ply") + " --runs 1 -q 8 --simplify 2,5 --json --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_TRUE(doc.contains("simplify")) << r.out;
  ASSERT_EQ(doc["simplify"].size(), 2u) << r.out;
  size_t previous = SIZE_MAX;
  for (const auto& row : doc["simplify"]) {
    const double bound = row["bound_percent"].get<double>();
    EXPECT_EQ(row["faces"].get<size_t>(), 320u);
    const size_t faces = row["tsm_faces"].get<size_t>();
    EXPECT_LT(faces, 320u) << row;
    EXPECT_LE(faces, previous) << "a looser bound keeps no more triangles";
    previous = faces;
    EXPECT_LE(row["tsm_measured_percent"].get<double>(), bound) << row;
    EXPECT_GE(row["tsm_measured_bound_percent"].get<double>(), row["tsm_measured_percent"].get<double>()) << row;
    if (!row.contains("meshopt_faces")) {
      EXPECT_FALSE(tsm_test::running_in_ci()) << "meshoptimizer (libmeshoptimizer-dev) is required in CI";
      continue;
    }
    EXPECT_LE(row["meshopt_faces"].get<size_t>(), 320u) << row;
    EXPECT_LE(row["meshopt_measured_percent"].get<double>(), bound) << row;
  }
  r = tsm("bench " + q("small.ply") + " --runs 1 -q 8 --simplify 1 --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("| small.ply | 320 | 1% |"), std::string::npos) << r.out;
  r = tsm("bench " + q("small.ply") + " --simplify 0");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
}

// A mesh with normals and texture coordinates gets a row in the attributes
// table: tsm's bytes by part and its exact round trip with the attributes,
// and Draco's smallest file of the same values (draco_encoder, installed by
// scripts/setup.sh, so in CI it must work).
TEST_F(Cli, BenchComparesAttributes) {
  ASSERT_TRUE(tsm::write_mesh(file("flat.obj"), tsm_test::flat_shaded_textured_sphere(2)).ok());
  Result r = tsm("bench " + q("flat.obj") + " --runs 1 -q 11 --json --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["attribute_files"].size(), 1u) << r.out;
  const auto& row = doc["attribute_files"][0];
  EXPECT_EQ(row["mesh"], "flat.obj");
  EXPECT_EQ(row["faces"], 320);
  EXPECT_EQ(row["points"], 162) << "the split vertices of one point count once";
  EXPECT_TRUE(row["tsm_exact"].get<bool>()) << r.out;
  const std::string parts = row["tsm_parts"].get<std::string>();
  EXPECT_NE(parts.find("normal "), std::string::npos) << parts;
  EXPECT_NE(parts.find("texcoord "), std::string::npos) << parts;
  if (!row.contains("draco_cl10_bytes")) {
    EXPECT_FALSE(tsm_test::running_in_ci()) << "draco_encoder (draco-tools) is required in CI: " << r.out;
    EXPECT_NE(row["draco_inputs"].get<std::string>().find("not installed"), std::string::npos) << r.out;
  } else {
    EXPECT_GT(row["draco_cl10_bytes"].get<size_t>(), 100u) << r.out;
    EXPECT_NE(row["draco_inputs"].get<std::string>().find("shared lists: "), std::string::npos) << r.out;
  }
  // A mesh without those attributes has no row.
  write_input("small.ply");
  r = tsm("bench " + q("small.ply") + " --runs 1 -q 8 --json --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["attribute_files"].empty()) << r.out;
}

// ---------------------------------------------------------------- many files, pipes, safety

// Lines of a text.
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// A pseudo-terminal: the tool sees a terminal on the side we give it.
struct Pty {
  int master = -1;
  std::string slave;
  Pty() {
    master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master >= 0 && grantpt(master) == 0 && unlockpt(master) == 0) slave = ptsname(master);
  }
  ~Pty() {
    if (master >= 0) close(master);
  }
  bool ok() const { return !slave.empty(); }
  // What the tool wrote (it has exited).
  std::string drain() const {
    std::string out;
    char buf[4096];
    while (poll_readable()) {
      ssize_t n = read(master, buf, sizeof buf);
      if (n <= 0) break;
      out.append(buf, static_cast<size_t>(n));
    }
    return out;
  }

 private:
  bool poll_readable() const {
    struct pollfd p = {master, POLLIN, 0};
    return poll(&p, 1, 50) > 0 && (p.revents & POLLIN);
  }
};

class CliBatch : public Cli {
 protected:
  // Three small meshes in three formats: a.ply, b.obj, c.off.
  std::vector<tsm::Mesh> write_three() {
    std::vector<tsm::Mesh> m = {tsm_test::icosphere(2), tsm_test::cube_quads(), tsm_test::book(4)};
    EXPECT_TRUE(tsm::write_mesh(file("a.ply"), m[0]).ok());
    EXPECT_TRUE(tsm::write_mesh(file("b.obj"), m[1]).ok());
    std::ostringstream off;
    off << "OFF\n" << m[2].vertex_count() << " " << m[2].face_count() << " 0\n";
    for (size_t v = 0; v < m[2].vertex_count(); ++v)
      off << m[2].positions[3 * v] << " " << m[2].positions[3 * v + 1] << " " << m[2].positions[3 * v + 2] << "\n";
    for (size_t f = 0; f < m[2].face_count(); ++f) {
      off << m[2].face_size(f);
      for (uint32_t c = 0; c < m[2].face_size(f); ++c) off << " " << m[2].face(f)[c];
      off << "\n";
    }
    spit(file("c.off"), off.str());
    return m;
  }

  // Files (not folders) under the work folder, recursively, whose name contains ".tmp-".
  int temporaries_anywhere() const {
    int n = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir.path))
      if (e.path().filename().string().find(".tmp-") != std::string::npos) ++n;
    return n;
  }

  void expect_same_mesh(const tsm::Mesh& original, const std::string& path, int q) {
    tsm::Mesh back;
    tsm::Status s = tsm::read_mesh(path, back);
    ASSERT_TRUE(s.ok()) << path << ": " << s.to_string();
    auto c = tsm::compare_meshes(original, back, q);
    EXPECT_TRUE(c.equal) << path << ": " << c.difference;
  }
};

TEST_F(CliBatch, HelpShowsTheNewOptionsWithExamples) {
  struct Expect {
    const char* cmd;
    std::vector<const char*> options;
  };
  for (const Expect& e : {Expect{"encode", {"--jobs", "--input-format", "--json", "--force", "--quiet", "-o"}},
                          Expect{"decode", {"--jobs", "--format", "--json", "--force", "--quiet", "--ascii"}},
                          Expect{"info", {"--jobs", "--json"}}}) {
    Result r = tsm(std::string(e.cmd) + " --help");
    ASSERT_EQ(r.code, 0) << e.cmd << ": " << r.err;
    for (const char* o : e.options) EXPECT_NE(r.out.find(o), std::string::npos) << e.cmd << " " << o << ":\n" << r.out;
    EXPECT_NE(r.out.find("Examples:\n  tsm " + std::string(e.cmd)), std::string::npos) << r.out;
  }
}

TEST_F(CliBatch, EncodeAndDecodeManyFilesIntoFolders) {
  std::vector<tsm::Mesh> m = write_three();
  Result r = tsm("encode " + q("a.ply") + " " + q("b.obj") + " " + q("c.off") + " -o " + q("packed") + " -q 12 -j 2");
  ASSERT_EQ(r.code, 0) << r.err;
  // One report per file, in input order whatever the order they finished in; a summary on stderr.
  std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  EXPECT_EQ(lines[0].rfind(file("a.ply") + ": 162 vertices", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find("packed/a.tsm"), std::string::npos) << lines[0];
  EXPECT_EQ(lines[1].rfind(file("b.obj") + ":", 0), 0u) << lines[1];
  EXPECT_EQ(lines[2].rfind(file("c.off") + ":", 0), 0u) << lines[2];
  EXPECT_NE(r.err.find("encoded 3 of 3 files"), std::string::npos) << r.err;
  for (const char* name : {"a", "b", "c"}) ASSERT_TRUE(fs::is_regular_file(file("packed/" + std::string(name) + ".tsm")));

  // decode: to a folder (created), PLY by default; OBJ with --format.
  const std::string tsms = q("packed/a.tsm") + " " + q("packed/b.tsm") + " " + q("packed/c.tsm");
  r = tsm("decode " + tsms + " -o " + q("back/") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "");
  r = tsm("decode " + tsms + " -o " + q("objs") + " --format obj --quiet -j 3");
  ASSERT_EQ(r.code, 0) << r.err;
  const char* names[] = {"a", "b", "c"};
  for (int i = 0; i < 3; ++i) {
    expect_same_mesh(m[static_cast<size_t>(i)], file("back/" + std::string(names[i]) + ".ply"), 12);
    expect_same_mesh(m[static_cast<size_t>(i)], file("objs/" + std::string(names[i]) + ".obj"), 12);
  }
  // A single file into an existing folder keeps its name.
  r = tsm("decode " + q("packed/b.tsm") + " -o " + q("objs") + " --format ply --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_same_mesh(m[1], file("objs/b.ply"), 12);
  // Without -o: beside each input.
  r = tsm("decode " + tsms + " --format obj --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* name : names) EXPECT_TRUE(fs::exists(file("packed/" + std::string(name) + ".obj")));
  // info takes many files too.
  r = tsm("info " + tsms);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("a.tsm: tsm format version"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("c.tsm: tsm format version"), std::string::npos) << r.out;
  EXPECT_LT(r.out.find("a.tsm: tsm"), r.out.find("b.tsm: tsm"));
  EXPECT_EQ(temporaries_anywhere(), 0);
}

TEST_F(CliBatch, OneBrokenFileDoesNotStopTheOthers) {
  write_three();
  spit(file("broken.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n");
  Result r = tsm("encode " + q("a.ply") + " " + q("broken.ply") + " " + q("b.obj") + " -o " + q("out") + " -j 2");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_TRUE(fs::exists(file("out/a.tsm")));
  EXPECT_TRUE(fs::exists(file("out/b.tsm")));
  EXPECT_FALSE(fs::exists(file("out/broken.tsm")));
  EXPECT_EQ(lines_of(r.out).size(), 2u) << r.out;
  // The failure is reported when it happens and listed again at the end.
  const size_t summary = r.err.find("1 of 3 files failed:");
  ASSERT_NE(summary, std::string::npos) << r.err;
  EXPECT_NE(r.err.find("broken.ply", summary), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("encoded 2 of 3 files"), std::string::npos) << r.err;

  // --json: one object per input, in order, the failure included.
  r = tsm("encode " + q("a.ply") + " " + q("broken.ply") + " " + q("b.obj") + " -o " + q("json") + " --json --quiet");
  EXPECT_EQ(r.code, 3) << r.err;
  std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  EXPECT_NE(lines[0].find("\"status\": \"ok\""), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("\"input\": \"" + file("broken.ply") + "\""), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("\"status\": \"error\", \"exit_code\": 3, \"error\": \""), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("line 3"), std::string::npos) << lines[1];
  EXPECT_NE(lines[2].find("\"status\": \"ok\""), std::string::npos) << lines[2];

  // decode: a corrupt file (bad input, 3) and an output that cannot be
  // written (I/O, 4) beside good files: the exit code is the worst class.
  std::string damaged = slurp(file("out/a.tsm"));
  damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x10);
  fs::create_directories(file("in"));
  spit(file("in/damaged.tsm"), damaged);
  fs::copy_file(file("out/a.tsm"), file("in/good.tsm"));
  fs::copy_file(file("out/b.tsm"), file("in/blocked.tsm"));
  fs::create_directories(file("dec/blocked.ply/sub"));  // a folder where the output should go
  r = tsm("decode " + q("in/damaged.tsm") + " " + q("in/good.tsm") + " " + q("in/blocked.tsm") + " -o " + q("dec") +
          " -f --quiet");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(fs::is_regular_file(file("dec/good.ply")));
  EXPECT_FALSE(fs::exists(file("dec/damaged.ply")));
  EXPECT_NE(r.err.find("2 of 3 files failed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("damaged.tsm"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("blocked.ply"), std::string::npos) << r.err;
  EXPECT_EQ(temporaries_anywhere(), 0);
}

TEST_F(CliBatch, ParallelRunsGiveTheSameBytesAsSerialRuns) {
  const std::vector<tsm::Mesh> meshes = {tsm_test::icosphere(3), tsm_test::genus_surface(2), tsm_test::grid_with_holes(20, 3),
                                         tsm_test::random_soup(300, 500, 7), tsm_test::moebius(30), tsm_test::bowtie()};
  std::string inputs;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const std::string name = "m" + std::to_string(i) + (i % 2 ? ".obj" : ".ply");
    ASSERT_TRUE(tsm::write_mesh(file(name), meshes[i]).ok());
    inputs += " " + q(name);
  }
  Result r = tsm("encode" + inputs + " -o " + q("serial") + " -j 1 -q 11 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string serial_json = r.out;
  r = tsm("encode" + inputs + " -o " + q("parallel") + " -j 2 -q 11 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lines_of(r.out).size(), meshes.size());
  std::string tsms_serial, tsms_parallel;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const std::string name = "m" + std::to_string(i);
    const std::string a = slurp(file("serial/" + name + ".tsm")), b = slurp(file("parallel/" + name + ".tsm"));
    EXPECT_FALSE(a.empty()) << name;
    EXPECT_EQ(a, b) << name;
    tsms_serial += " " + q("serial/" + name + ".tsm");
    tsms_parallel += " " + q("parallel/" + name + ".tsm");
    // The JSON lines come in input order in both runs.
    EXPECT_NE(lines_of(r.out)[i].find("\"input\": \"" + file(name)), std::string::npos) << r.out;
    EXPECT_NE(lines_of(serial_json)[i].find("\"input\": \"" + file(name)), std::string::npos) << serial_json;
  }
  ASSERT_EQ(tsm("decode" + tsms_serial + " -o " + q("dec1") + " -j 1 --quiet").code, 0);
  ASSERT_EQ(tsm("decode" + tsms_parallel + " -o " + q("dec2") + " -j 2 --quiet").code, 0);
  for (size_t i = 0; i < meshes.size(); ++i) {
    const std::string name = "m" + std::to_string(i) + ".ply";
    EXPECT_EQ(slurp(file("dec1/" + name)), slurp(file("dec2/" + name))) << name;
    expect_same_mesh(meshes[i], file("dec2/" + name), 11);
  }
}

TEST_F(CliBatch, NeverOverwritesWithoutForce) {
  write_three();
  fs::create_directories(file("out"));
  spit(file("out/b.tsm"), "keep me");
  Result r = tsm("encode " + q("a.ply") + " " + q("b.obj") + " " + q("c.off") + " -o " + q("out") + " --quiet");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find(file("out/b.tsm") + ": already exists; pass -f (--force) to overwrite it"), std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(file("out/b.tsm")), "keep me");
  EXPECT_TRUE(fs::exists(file("out/a.tsm")));  // the others are written
  EXPECT_TRUE(fs::exists(file("out/c.tsm")));
  r = tsm("encode " + q("a.ply") + " " + q("b.obj") + " " + q("c.off") + " -o " + q("out") + " --quiet -f");
  EXPECT_EQ(r.code, 0) << r.err;
  tsm::FileInfo fi;
  EXPECT_TRUE(tsm::inspect(slurp(file("out/b.tsm")), fi).ok());

  // Same for decode.
  fs::create_directories(file("dec"));
  spit(file("dec/c.ply"), "keep me too");
  r = tsm("decode " + q("out/a.tsm") + " " + q("out/c.tsm") + " -o " + q("dec") + " --quiet");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find(file("dec/c.ply") + ": already exists; pass -f"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(file("dec/c.ply")), "keep me too");
  EXPECT_TRUE(fs::exists(file("dec/a.ply")));
  r = tsm("decode " + q("out/a.tsm") + " " + q("out/c.tsm") + " -o " + q("dec") + " --quiet -f");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(file("dec/c.ply")), "keep me too");
  EXPECT_EQ(temporaries_anywhere(), 0);
}

TEST_F(CliBatch, TwoInputsOntoOneOutputAreRefused) {
  write_three();
  fs::create_directories(file("x"));
  fs::copy_file(file("a.ply"), file("x/b.ply"));
  Result r = tsm("encode " + q("a.ply") + " " + q("b.obj") + " " + q("x/b.ply") + " -o " + q("out"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(file("b.obj") + " and " + file("x/b.ply") + " would both be written to"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(file("out")));  // refused before anything is done
  // The same file twice is the same clash.
  r = tsm("encode " + q("a.ply") + " " + q("a.ply") + " -o " + q("out"));
  EXPECT_EQ(r.code, 2) << r.err;
}

TEST_F(CliBatch, StdinStdoutPipeRoundTrip) {
  tsm::Mesh m = tsm_test::icosphere(2);
  ASSERT_TRUE(tsm::write_mesh(file("in.obj"), m).ok());
  ASSERT_TRUE(tsm::write_mesh(file("in.ply"), m).ok());
  // OBJ has no signature: --input-format says what stdin is.
  Result r = sh("$TSM encode - --input-format obj -q 12 <" + q("in.obj") + " | $TSM decode - --format ply >" +
                q("back.ply"));
  ASSERT_EQ(r.code, 0) << r.err;
  expect_same_mesh(m, file("back.ply"), 12);
  // The reports go to stderr when stdout carries the data; --quiet silences them.
  EXPECT_NE(r.err.find("<stdin>: 162 vertices, 320 faces -> <stdout>"), std::string::npos) << r.err;
  r = sh("$TSM encode - --input-format obj -q 12 --quiet <" + q("in.obj") + " | $TSM decode - --format obj --quiet >" +
         q("back.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  expect_same_mesh(m, file("back.obj"), 12);

  // PLY is recognized from its content; the bytes equal those of a file-to-file run.
  ASSERT_EQ(tsm("encode " + q("in.ply") + " -o " + q("ref.tsm") + " --quiet").code, 0);
  r = sh("$TSM encode - --quiet <" + q("in.ply") + " >" + q("piped.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(file("piped.tsm")), slurp(file("ref.tsm")));
  // -o - with a file input, and stdin to a file.
  r = sh("$TSM encode " + q("in.ply") + " -o - --quiet | $TSM decode - -o " + q("back2.ply") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_same_mesh(m, file("back2.ply"), tsm::kDefaultQuantizationBits);
  // info reads stdin too.
  r = sh("$TSM info - --json <" + q("ref.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"file\": \"-\", \"status\": \"ok\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"vertices\": 162"), std::string::npos) << r.out;

  // An OBJ on stdin without --input-format, an empty stdin, junk: bad input, said clearly.
  r = sh("$TSM encode - <" + q("in.obj") + " >" + q("x.tsm"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("<stdin>: cannot tell the mesh format"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--input-format"), std::string::npos) << r.err;
  r = sh("$TSM encode - </dev/null >" + q("x.tsm"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("stdin was empty"), std::string::npos) << r.err;
  r = sh("$TSM decode - <" + q("in.obj") + " >" + q("x.ply"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("<stdin>: "), std::string::npos) << r.err;
  EXPECT_EQ(temporaries_anywhere(), 0);
}

TEST_F(CliBatch, StdinAndStdoutMisuseIsRefused) {
  write_three();
  struct Case {
    std::string args, says;
  };
  for (const Case& c : std::vector<Case>{
           {"encode " + q("a.ply") + " " + q("b.obj") + " -o -", "single input"},
           {"encode - " + q("a.ply") + " -o " + q("out"), "only input"},
           {"encode " + q("a.ply") + " -o - --json", "--json"},
           {"decode - -o " + q("folder/"), "stdin has no name"}}) {
    Result r = sh("$TSM " + c.args + " <" + q("a.ply") + " >" + q("sink"));
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << ": " << r.err;
    EXPECT_EQ(slurp(file("sink")), "") << c.args;
  }
  // Binary data is not written to a terminal; text is.
  Pty pty;
  ASSERT_TRUE(pty.ok());
  ASSERT_EQ(tsm("encode " + q("b.obj") + " -o " + q("b.tsm") + " --quiet").code, 0);
  Result r = sh("$TSM encode " + q("a.ply") + " -o - >" + quote(pty.slave));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("refusing to write binary .tsm data to a terminal"), std::string::npos) << r.err;
  r = sh("$TSM decode - <" + q("b.tsm") + " >" + quote(pty.slave));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("binary PLY to a terminal"), std::string::npos) << r.err;
  r = sh("$TSM decode " + q("b.tsm") + " -o - --format obj --quiet >" + quote(pty.slave));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(pty.drain().find("v "), std::string::npos);
  // "-" with a terminal on stdin would wait for typing: refused.
  r = sh("$TSM decode - -o " + q("x.ply") + " <" + quote(pty.slave));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("stdin is a terminal"), std::string::npos) << r.err;
}

TEST_F(CliBatch, BadBatchArgumentsExitTwo) {
  write_three();
  spit(file("plain"), "x");
  for (const std::string& args : std::vector<std::string>{
           "encode " + q("a.ply") + " -j -1", "encode " + q("a.ply") + " -j x", "encode " + q("a.ply") + " --input-format fbx",
           "decode " + q("a.ply") + " --format fbx", "decode " + q("a.ply") + " -o " + q("x.ply") + " --format obj",
           "encode " + q("a.ply") + " " + q("b.obj") + " -o " + q("plain"),
           "encode " + q("a.ply") + " " + q("b.obj") + " -o " + q("out.tsm")}) {
    Result r = tsm(args);
    EXPECT_EQ(r.code, 2) << "tsm " << args << "\n" << r.out << r.err;
    EXPECT_FALSE(r.err.empty()) << "tsm " << args << ": says nothing";
  }
  EXPECT_FALSE(fs::exists(file("out.tsm")));
  EXPECT_EQ(slurp(file("plain")), "x");
}

TEST_F(CliBatch, JsonResultsForEveryCommand) {
  write_three();
  Result r = tsm("encode " + q("a.ply") + " -o " + q("a.tsm") + " -q 10 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string size = std::to_string(fs::file_size(file("a.tsm")));
  for (const std::string& field :
       {"{\"input\": \"" + file("a.ply") + "\", \"output\": \"" + file("a.tsm") + "\", \"status\": \"ok\", \"exit_code\": 0, \"error\": null",
        std::string("\"input_format\": \"ply\""), "\"bytes_in\": " + std::to_string(fs::file_size(file("a.ply"))),
        "\"bytes_out\": " + size, std::string("\"vertices\": 162"), std::string("\"faces\": 320"),
        std::string("\"bits_per_vertex\": "), std::string("\"quantization_bits\": 10"), std::string("\"ms\": ")})
    EXPECT_NE(r.out.find(field), std::string::npos) << field << "\n" << r.out;
  EXPECT_EQ(r.out.back(), '\n');
  EXPECT_EQ(lines_of(r.out).size(), 1u);
  EXPECT_EQ(r.out.substr(r.out.size() - 2), "}\n");

  r = tsm("decode " + q("a.tsm") + " -o " + q("a.obj") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const std::string& field : {std::string("\"status\": \"ok\""), std::string("\"output_format\": \"obj\""),
                                   "\"bytes_in\": " + size, "\"bytes_out\": " + std::to_string(fs::file_size(file("a.obj"))),
                                   std::string("\"vertices\": 162"), std::string("\"decode_ms\": ")})
    EXPECT_NE(r.out.find(field), std::string::npos) << field << "\n" << r.out;

  // A failure is a JSON line too, and info gives one line per file.
  spit(file("junk.tsm"), "junk");
  r = tsm("info " + q("a.tsm") + " " + q("junk.tsm") + " --json");
  EXPECT_EQ(r.code, 3) << r.err;
  std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 2u) << r.out;
  EXPECT_EQ(lines[0].rfind("{\"file\": \"" + file("a.tsm") + "\", \"status\": \"ok\"", 0), 0u) << lines[0];
  EXPECT_EQ(lines[1].rfind("{\"file\": \"" + file("junk.tsm") + "\", \"status\": \"error\", \"exit_code\": 3", 0), 0u)
      << lines[1];
  r = tsm("decode " + q("junk.tsm") + " -o " + q("j.ply") + " --json");
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.out.find("\"status\": \"error\""), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("junk.tsm"), std::string::npos) << r.err;
}

TEST_F(CliBatch, ProgressBarOnlyOnATerminalAndNotWhenQuiet) {
  write_three();
  const std::string inputs = q("a.ply") + " " + q("b.obj") + " " + q("c.off");
  // Not a terminal (a file): no bar, whatever the delay.
  Result r = sh("TSM_PROGRESS_AFTER_MS=0 $TSM encode " + inputs + " -o " + q("o1") + " </dev/null");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("[1/3]"), std::string::npos) << r.err;
  // A terminal: "[k/3] name" lines, erased before anything else is printed.
  Pty pty;
  ASSERT_TRUE(pty.ok());
  r = sh("TSM_PROGRESS_AFTER_MS=0 $TSM encode " + inputs + " -o " + q("o2") + " </dev/null 2>" + quote(pty.slave));
  ASSERT_EQ(r.code, 0) << r.err;
  std::string seen = pty.drain();
  EXPECT_NE(seen.find("/3] ["), std::string::npos) << seen;
  EXPECT_NE(seen.find("\r\x1b[K"), std::string::npos) << seen;
  EXPECT_NE(seen.find("encoded 3 of 3 files"), std::string::npos) << seen;
  // --quiet: nothing at all.
  r = sh("TSM_PROGRESS_AFTER_MS=0 $TSM encode " + inputs + " -o " + q("o3") + " --quiet </dev/null 2>" +
         quote(pty.slave));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(pty.drain(), "");
  // Work shorter than the delay shows no bar. A delay of ten minutes, not the
  // default second: under a sanitizer on a loaded machine three encodes can
  // take longer than a second (the test once failed that way).
  r = sh("TSM_PROGRESS_AFTER_MS=600000 $TSM encode " + inputs + " -o " + q("o4") + " </dev/null 2>" + quote(pty.slave));
  ASSERT_EQ(r.code, 0) << r.err;
  seen = pty.drain();
  EXPECT_EQ(seen.find("/3]"), std::string::npos) << seen;
}

// Starts the tool with stdin from a pipe (returned in *to_stdin) and stdout
// and stderr into files; returns the child's pid.
pid_t spawn_tsm(const std::vector<std::string>& args, int* to_stdin, const std::string& out, const std::string& err) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  std::vector<std::string> all = {TSM_CLI_PATH};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = fork();
  if (pid == 0) {
    // As from an interactive shell: default signal actions, nothing blocked.
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) signal(sig, SIG_DFL);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    int o = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644), e = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fds[0], 0);
    dup2(o, 1);
    dup2(e, 2);
    close(fds[0]);
    close(fds[1]);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(fds[0]);
  *to_stdin = fds[1];
  return pid;
}

// waitpid with a deadline (a hung child is killed and reported).
bool wait_child(pid_t pid, int& status) {
  for (int i = 0; i < 1000; ++i) {
    if (waitpid(pid, &status, WNOHANG) == pid) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return false;
}

TEST_F(CliBatch, KilledDecodeLeavesNoOutputAndNoTemporary) {
  // The decode is stopped half-way through its input (the pipe feeding it
  // stays open), then killed: by SIGKILL, and by the signals a user or a
  // build system sends (SIGTERM, SIGINT), which also end it by that signal.
  write_input();
  ASSERT_EQ(tsm("encode " + q("in.ply") + " -o " + q("in.tsm") + " --quiet").code, 0);
  const std::string bytes = slurp(file("in.tsm"));
  for (int sig : {SIGKILL, SIGTERM, SIGINT}) {
    int to_stdin = -1;
    pid_t pid = spawn_tsm({"decode", "-", "-o", file("out.ply")}, &to_stdin, logs.file("out"), logs.file("err"));
    ASSERT_GT(pid, 0);
    ASSERT_EQ(write(to_stdin, bytes.data(), bytes.size() / 2), static_cast<ssize_t>(bytes.size() / 2));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    kill(pid, sig);
    int status = 0;
    EXPECT_TRUE(wait_child(pid, status)) << "signal " << sig << ": the tool did not end";
    close(to_stdin);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "signal " << sig << ", status " << status;
    EXPECT_FALSE(fs::exists(file("out.ply"))) << "signal " << sig;
    EXPECT_EQ(temporaries(), 0) << "signal " << sig;
  }
}

TEST_F(CliBatch, InterruptedBatchLeavesOnlyWholeFiles) {
  // A batch of decodes interrupted at different moments: whatever was being
  // done (reading, decoding, writing), every output is absent or complete,
  // and no temporary file is left, because the tool lets a write in progress
  // finish (or not start) before it ends.
  const tsm::Mesh big = tsm_test::copies(tsm_test::icosphere(4), 8);
  std::string packed;
  ASSERT_TRUE(tsm::encode(big, tsm::EncodeOptions{}, packed).ok());
  std::vector<std::string> args = {"decode"};
  for (int i = 0; i < 6; ++i) {
    spit(file("m" + std::to_string(i) + ".tsm"), packed);
    args.push_back(file("m" + std::to_string(i) + ".tsm"));
  }
  ASSERT_EQ(tsm("decode " + q("m0.tsm") + " -o " + q("reference.ply") + " --quiet").code, 0);
  const std::string reference = slurp(file("reference.ply"));
  args.insert(args.end(), {"-o", file("out"), "-j", "2", "-f", "--quiet"});
  for (int delay_ms : {0, 5, 15, 30, 60}) {
    int to_stdin = -1;
    pid_t pid = spawn_tsm(args, &to_stdin, logs.file("out"), logs.file("err"));
    ASSERT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    kill(pid, SIGTERM);
    int status = 0;
    EXPECT_TRUE(wait_child(pid, status)) << "after " << delay_ms << " ms: the tool did not end";
    close(to_stdin);
    EXPECT_TRUE((WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) || (WIFEXITED(status) && WEXITSTATUS(status) == 0))
        << "after " << delay_ms << " ms: status " << status;
    EXPECT_EQ(temporaries_anywhere(), 0) << "after " << delay_ms << " ms";
    if (fs::is_directory(file("out"))) {
      for (const auto& e : fs::directory_iterator(file("out"))) {
        EXPECT_TRUE(slurp(e.path().string()) == reference) << e.path() << " after " << delay_ms << " ms is not whole";
      }
    }
    fs::remove_all(file("out"));
  }
}

TEST_F(CliBatch, AWriteThatFailsLeavesNothing) {
  // A file size limit hit while the temporary is written (the process would
  // otherwise be killed by SIGXFSZ mid-write): a clean I/O error, exit 4, no
  // output, no temporary. The temporary's name is the output's + ".tmp-XXXXXX".
  write_input();
  ASSERT_EQ(tsm("encode " + q("in.ply") + " -o " + q("in.tsm") + " --quiet").code, 0);
  Result r = sh("ulimit -f 2; $TSM decode " + q("in.tsm") + " -o " + q("out.ply") + " --ascii </dev/null");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_NE(r.err.find(file("out.ply") + ": write failed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nothing was written"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file("out.ply")));
  EXPECT_EQ(temporaries(), 0);
}

// ---------------------------------------------------------------- inputs, outputs, messages

// Every line of the text is one valid JSON object (parsed by the JSON library).
::testing::AssertionResult json_lines(const std::string& text, size_t expected) {
  std::vector<std::string> lines = lines_of(text);
  if (lines.size() != expected)
    return ::testing::AssertionFailure() << lines.size() << " lines, expected " << expected << ":\n" << text;
  for (const std::string& l : lines) {
    try {
      if (!nlohmann::json::parse(l).is_object()) return ::testing::AssertionFailure() << "not an object: " << l;
    } catch (const std::exception& e) {
      return ::testing::AssertionFailure() << "invalid JSON (" << e.what() << "): " << l;
    }
  }
  return ::testing::AssertionSuccess();
}

// No byte of the text is a control character other than a line feed, and
// it is valid UTF-8 (the tool never echoes raw bytes of a file).
::testing::AssertionResult clean_text(const std::string& text) {
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if ((c < 0x20 && c != '\n') || c == 0x7F || c >= 0x80)  // the tool's messages are ASCII
      return ::testing::AssertionFailure() << "byte " << i << " is 0x" << std::hex << static_cast<int>(c) << ": " << text;
  }
  return ::testing::AssertionSuccess();
}

TEST_F(CliBatch, MissingFilesAndFoldersAreFailedInputsTheOthersGoOn) {
  write_three();
  fs::create_directories(file("folder"));
  Result r = tsm("encode " + q("missing.ply") + " " + q("a.ply") + " " + q("folder") + " " + q("b.obj") + " -o " +
                 q("out/") + " --json");
  EXPECT_EQ(r.code, 4) << r.err;  // cannot read a file: I/O (the worst class here)
  EXPECT_TRUE(fs::is_regular_file(file("out/a.tsm")));
  EXPECT_TRUE(fs::is_regular_file(file("out/b.tsm")));
  EXPECT_FALSE(fs::exists(file("out/missing.tsm")));
  EXPECT_FALSE(fs::exists(file("out/folder.tsm")));
  ASSERT_TRUE(json_lines(r.out, 4));
  const std::vector<std::string> lines = lines_of(r.out);
  const auto j0 = nlohmann::json::parse(lines[0]), j1 = nlohmann::json::parse(lines[1]),
             j2 = nlohmann::json::parse(lines[2]), j3 = nlohmann::json::parse(lines[3]);
  EXPECT_EQ(j0["input"], file("missing.ply"));
  EXPECT_EQ(j0["status"], "error");
  EXPECT_EQ(j0["exit_code"], 4);
  EXPECT_NE(j0["error"].get<std::string>().find("no such file"), std::string::npos) << lines[0];
  EXPECT_EQ(j1["status"], "ok");
  EXPECT_EQ(j2["exit_code"], 4);
  EXPECT_NE(j2["error"].get<std::string>().find("is a folder"), std::string::npos) << lines[2];
  EXPECT_EQ(j3["status"], "ok");
  EXPECT_NE(r.err.find("2 of 4 files failed"), std::string::npos) << r.err;

  // decode and info likewise.
  r = tsm("decode " + q("missing.tsm") + " " + q("out/a.tsm") + " -o " + q("dec/") + " --quiet");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(fs::is_regular_file(file("dec/a.ply")));
  r = tsm("info " + q("missing.tsm") + " " + q("out/a.tsm") + " " + q("folder") + " --json");
  EXPECT_EQ(r.code, 4) << r.err;
  ASSERT_TRUE(json_lines(r.out, 3));
  EXPECT_NE(lines_of(r.out)[1].find("\"status\": \"ok\""), std::string::npos) << r.out;
}

TEST_F(CliBatch, JsonIsValidForFileNamesThatAreNotUtf8) {
  write_input("caf\xE9.ply");  // Latin-1: not UTF-8
  write_input("ok.ply");
  Result r = tsm("encode " + q("caf\xE9.ply") + " " + q("ok.ply") + " " + q("caf\xE9-missing.ply") + " -o " + q("out/") +
                 " --json --quiet");
  EXPECT_EQ(r.code, 4) << r.err;
  ASSERT_TRUE(json_lines(r.out, 3));
  const auto j = nlohmann::json::parse(lines_of(r.out)[0]);
  // The odd byte shows as U+FFFD (the replacement character).
  EXPECT_EQ(j["input"], file("caf\xEF\xBF\xBD.ply"));
  EXPECT_EQ(j["status"], "ok");
  EXPECT_GT(j["compression_ratio"].get<double>(), 1.0);
  ASSERT_TRUE(fs::is_regular_file(file("out/caf\xE9.tsm")));
  r = tsm("info " + q("out/caf\xE9.tsm") + " --json");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(json_lines(r.out, 1));
  // Text output shows the byte escaped.
  r = tsm("encode " + q("caf\xE9.ply") + " -o " + q("text.tsm"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("caf\\xE9.ply"), std::string::npos) << r.out;
  EXPECT_TRUE(clean_text(r.out + r.err));
}

TEST_F(Cli, InputThatIsNotAMeshIsBadInput) {
  // A PNG named .obj: binary where OBJ text is expected; never echoed raw.
  std::string png("\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x10\0\0\0\x10\x08\x06\0\0\0\x1f\xf3\xff" "a", 33);
  png += std::string("\x1b[2J\x1b]0;pwned\x07", 13);
  spit(file("picture.obj"), png);
  Result r = tsm("encode " + q("picture.obj") + " -o " + q("picture.tsm"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("picture.obj: not a mesh"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("binary data"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("\\x89PNG"), std::string::npos) << r.err;
  EXPECT_TRUE(clean_text(r.out + r.err));
  EXPECT_FALSE(fs::exists(file("picture.tsm")));

  // Text that is no OBJ.
  spit(file("hello.obj"), "hello world\n");
  r = tsm("encode " + q("hello.obj") + " -o " + q("hello.tsm"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("line 1 (\"hello world\") is not an OBJ statement"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file("hello.tsm")));

  // A PLY read as OBJ because the command line says so: binary and ASCII PLY.
  write_input("bin.ply");
  tsm::WriteOptions ascii;
  ascii.ascii = true;
  ASSERT_TRUE(tsm::write_mesh(file("text.ply"), tsm_test::icosphere(1), ascii).ok());
  for (const char* name : {"bin.ply", "text.ply"}) {
    r = tsm("encode " + q(name) + " --input-format obj -o " + q("x.tsm"));
    EXPECT_EQ(r.code, 3) << name << ": " << r.err;
    EXPECT_NE(r.err.find("looks like PLY: drop --input-format obj"), std::string::npos) << name << ": " << r.err;
    EXPECT_TRUE(clean_text(r.err)) << name;
    EXPECT_FALSE(fs::exists(file("x.tsm")));
  }

  // An empty OBJ, or one with comments and groups only, is an empty mesh: encoded, and said so.
  spit(file("empty.obj"), "");
  spit(file("comments.obj"), "# nothing here\n\no thing\ng group\n");
  for (const char* name : {"empty.obj", "comments.obj"}) {
    r = tsm("encode " + q(name) + " -o " + q(std::string(name) + ".tsm"));
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    EXPECT_NE(r.err.find("empty mesh"), std::string::npos) << name << ": " << r.err;
    EXPECT_TRUE(fs::is_regular_file(file(std::string(name) + ".tsm")));
  }
}

TEST_F(CliBatch, OutputNamesSayWhatTheyHold) {
  write_three();
  // A file name for several inputs: refused, nothing made.
  Result r = tsm("encode " + q("a.ply") + " " + q("b.obj") + " -o " + q("both.obj"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("give a folder"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file("both.obj")));
  r = tsm("decode " + q("a.ply") + " " + q("b.obj") + " -o " + q("both.tsm"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_FALSE(fs::exists(file("both.tsm")));

  // encode writes .tsm: a mesh name for it is refused, with the name to use.
  for (const char* name : {"x.ply", "x.obj", "x.stl", "x.off"}) {
    r = tsm("encode " + q("a.ply") + " -o " + q(name));
    EXPECT_EQ(r.code, 2) << name << ": " << r.err;
    EXPECT_NE(r.err.find(file("x.tsm")), std::string::npos) << name << ": " << r.err;
    EXPECT_NE(r.err.find("tsm decode"), std::string::npos) << name << ": " << r.err;
    EXPECT_FALSE(fs::exists(file(name))) << name;
  }
  // A glTF name: a glTF with TSM_mesh_compression (one input only); decode
  // gives a plain glTF back; --fallback is for glTF outputs only.
  for (const char* name : {"x.glb", "x.gltf"}) {
    r = tsm("encode " + q("a.ply") + " " + q("b.obj") + " -o " + q(name));
    EXPECT_EQ(r.code, 2) << name << ": " << r.err;
    EXPECT_NE(r.err.find("takes one input file"), std::string::npos) << r.err;
    r = tsm("encode " + q("a.ply") + " -o " + q(name) + " --quiet");
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    EXPECT_NE(slurp(file(name)).find("\"extensionsRequired\":[\"TSM_mesh_compression\"]"), std::string::npos) << name;
    r = tsm("encode " + q("a.ply") + " -o " + q(name));
    EXPECT_EQ(r.code, 2) << name << ": " << r.err;
    EXPECT_NE(r.err.find("already exists"), std::string::npos) << r.err;
    r = tsm("decode " + q(name) + " -o " + q("plain.glb") + " -f --quiet");
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    EXPECT_EQ(slurp(file("plain.glb")).find("TSM_mesh_compression"), std::string::npos) << name;
  }
  EXPECT_TRUE(fs::is_regular_file(file("x.bin")));
  r = tsm("encode " + q("a.ply") + " -o " + q("x2.tsm") + " --fallback");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--fallback"), std::string::npos) << r.err;
  // Missing folders of a single output are created.
  r = tsm("encode " + q("a.ply") + " -o " + q("nodir/x/y.tsm") + " --quiet");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(file("nodir/x/y.tsm")));
  r = tsm("decode " + q("nodir/x/y.tsm") + " -o " + q("deep/er/a.obj") + " --quiet");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(file("deep/er/a.obj")));
  EXPECT_EQ(temporaries_anywhere(), 0);
}

TEST_F(CliBatch, EveryHintLeadsSomewhere) {
  write_input();
  ASSERT_EQ(tsm("encode " + q("in.ply") + " -o " + q("in.tsm") + " --quiet").code, 0);

  // An output name that does not say the format: both remedies offered work.
  Result r = tsm("decode " + q("in.tsm") + " -o " + q("rt.xyz"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--format"), std::string::npos) << r.err;
  EXPECT_EQ(tsm("decode " + q("in.tsm") + " -o " + q("rt.xyz") + " --format ply --quiet").code, 0);
  EXPECT_EQ(tsm("decode " + q("in.tsm") + " -o " + q("rt.ply") + " --quiet").code, 0);
  // An STL name: written, or refused with a hint that is not --format (which the name would contradict).
  r = tsm("decode " + q("in.tsm") + " -o " + q("rt.stl") + " --quiet");
  if (r.code != 0) {
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.find("--format"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("rt.ply"), std::string::npos) << r.err;
  }

  // --ascii is for PLY output.
  r = tsm("decode " + q("in.tsm") + " -o " + q("rt.obj") + " --ascii");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("OBJ is text already: drop --ascii"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file("rt.obj")));
  EXPECT_EQ(tsm("decode " + q("in.tsm") + " -o " + q("rt2.ply") + " --ascii --quiet").code, 0);

  // NaN coordinates: the hint (--lossless --allow-nonfinite) is followed and works.
  spit(file("nan.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 1\nproperty list uchar int vertex_indices\nend_header\nnan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  spit(file("nan.obj"), "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  for (const char* name : {"nan.ply", "nan.obj"}) {
    for (const char* flag : {"", " --allow-nonfinite"}) {
      r = tsm("encode " + q(name) + " -o " + q("nan.tsm") + flag);
      EXPECT_EQ(r.code, 3) << name << flag << ": " << r.err;
      EXPECT_NE(r.err.find("--lossless --allow-nonfinite"), std::string::npos) << name << flag << ": " << r.err;
      EXPECT_NE(r.err.find("fix or drop"), std::string::npos) << name << flag << ": " << r.err;
    }
    r = tsm("encode " + q(name) + " -o " + q(std::string(name) + ".tsm") + " --lossless --allow-nonfinite --quiet");
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
  }

  // A .gltf on stdin whose buffer is a file: what to do on the command line.
  std::string bin;
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) bin.append(reinterpret_cast<const char*>(&f), 4);
  spit(file("tri.bin"), bin);
  spit(file("tri.gltf"), R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
    "buffers": [{"byteLength": 36, "uri": "tri.bin"}], "bufferViews": [{"buffer": 0, "byteLength": 36}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}]})");
  r = sh("$TSM encode - -o " + q("tri.tsm") + " < " + q("tri.gltf"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("give the .gltf file's path instead of -"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("ReadOptions"), std::string::npos) << r.err;
  r = tsm("encode " + q("tri.gltf") + " -o " + q("tri.tsm"));
  EXPECT_EQ(r.code, 0) << r.err;
  // With normals, and --drop-attributes: the glTF document kept for the way
  // back named the NORMAL accessor, so it is dropped too and decoding to
  // glTF writes the positions and faces (it failed: "the mesh has no vertex
  // attribute 'normal'").
  for (float f : {0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f}) bin.append(reinterpret_cast<const char*>(&f), 4);
  spit(file("trin.bin"), bin);
  spit(file("trin.gltf"), R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}],
    "buffers": [{"byteLength": 72, "uri": "trin.bin"}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 36}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
                  {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}]})");
  r = tsm("encode " + q("trin.gltf") + " -o " + q("trin.tsm") + " --drop-attributes --quiet");
  EXPECT_EQ(r.code, 0) << r.err;
  r = tsm("decode " + q("trin.tsm") + " -o " + q("trin_back.glb") + " --quiet");
  EXPECT_EQ(r.code, 0) << r.err;
  tsm::Mesh back;
  ASSERT_TRUE(tsm::read_mesh(file("trin_back.glb"), back).ok());
  EXPECT_EQ(back.face_count(), 1u);
  EXPECT_TRUE(back.attributes.empty());

  // Unknown options and commands: the nearest one is named.
  r = tsm("encode " + q("in.ply") + " --qbits 12");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("unknown option --qbits"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("did you mean -q/--quantization?"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("File does not exist"), std::string::npos) << r.err;
  r = tsm("encode " + q("in.ply") + " --levle 3");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("did you mean -l/--level?"), std::string::npos) << r.err;
  r = tsm("encode " + q("in.ply") + " --frobnicate");  // nothing near: no guess
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("unknown option --frobnicate"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("did you mean"), std::string::npos) << r.err;
  r = tsm("encdoe " + q("in.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("did you mean 'tsm encode'?"), std::string::npos) << r.err;
  r = tsm("");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("encode, decode, info, bench, compare or simplify"), std::string::npos) << r.err;
}

TEST_F(CliBatch, ReportsSpeakPlainly) {
  tsm::Mesh one;
  one.add_vertex(0, 0, 0);
  one.add_vertex(1, 0, 0);
  one.add_vertex(0, 1, 0);
  one.add_triangle(0, 1, 2);
  ASSERT_TRUE(tsm::write_mesh(file("one.ply"), one).ok());
  Result r = tsm("encode " + q("one.ply") + " -o " + q("one.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("3 vertices, 1 face -> "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" (ratio "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("1 faces"), std::string::npos) << r.out;
  r = tsm("decode " + q("one.tsm") + " -o " + q("one-back.ply"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("3 vertices, 1 face, decode"), std::string::npos) << r.out;

  // A short batch reports milliseconds, not "0.0 s": under a second the
  // summary says ms, from a second on (a loaded machine, a sanitizer) seconds.
  write_three();
  r = tsm("encode " + q("a.ply") + " " + q("b.obj") + " -o " + q("out/"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("in 0.0 s"), std::string::npos) << r.err;
  const size_t in = r.err.rfind(" in ");
  ASSERT_NE(in, std::string::npos) << r.err;
  const std::string took = r.err.substr(in + 4);
  if (took.find(" ms\n") == std::string::npos) {
    ASSERT_NE(took.find(" s\n"), std::string::npos) << r.err;
    EXPECT_GE(std::stod(took), 1.0) << r.err;
  }
}

// Draco's glTF reader runs in the same process as tsm's (bench): neither
// copy of tinygltf may stand in for the other. Runs under ASan too.
TEST_F(Cli, BenchReadsGltfAndGlb) {
  ASSERT_TRUE(tsm::write_mesh(file("small.gltf"), tsm_test::icosphere(2)).ok());
  ASSERT_TRUE(tsm::write_mesh(file("small.glb"), tsm_test::icosphere(1)).ok());
  std::vector<std::string> meshes = {file("small.gltf"), file("small.glb")};
  for (const char* rel : {"assets/VertexColorTest/VertexColorTest.gltf", "assets/Fox/Fox.gltf"})
    if (fs::is_regular_file(tsm_test::corpus_file(rel))) meshes.push_back(tsm_test::corpus_file(rel));
  for (const std::string& m : meshes) {
    Result r = tsm("bench " + quote(m) + " --runs 1 -q 11 --quiet");
    EXPECT_EQ(r.code, 0) << m << ":\n" << r.out << r.err;
    EXPECT_NE(r.out.find("| " + fs::path(m).filename().string() + " |"), std::string::npos) << r.out;
  }
}

// A glTF file gets a row in the assets table: tsm's .glb and geometry bytes
// and decode time, and the same for draco_transcoder and gltfpack when they
// are installed (scripts/setup.sh installs both, so in CI they must work).
TEST_F(Cli, BenchComparesGltfAssets) {
  ASSERT_TRUE(tsm::write_mesh(file("ball.glb"), tsm_test::icosphere(3)).ok());
  Result r = tsm("bench " + quote(file("ball.glb")) + " --runs 1 -q 11 --json --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["assets"].size(), 1u) << r.out;
  const auto& row = doc["assets"][0];
  EXPECT_EQ(row["asset"], "ball.glb");
  EXPECT_EQ(row["vertices"], 642);
  EXPECT_EQ(row["triangles"], 1280);
  EXPECT_EQ(row["input_bytes"].get<size_t>(), fs::file_size(file("ball.glb")));
  const auto& t = row["tsm"];
  ASSERT_TRUE(t["ok"].get<bool>()) << r.out;
  // The geometry is the stream: far smaller than the 642 float positions and 1,280 triangles.
  EXPECT_GT(t["geometry_bytes"].get<size_t>(), 100u) << r.out;
  EXPECT_LT(t["geometry_bytes"].get<size_t>(), 642u * 12 / 3) << r.out;
  EXPECT_LT(t["geometry_bytes"].get<size_t>(), t["glb_bytes"].get<size_t>()) << r.out;
  EXPECT_GT(t["decode_ms"].get<double>(), 0.0) << r.out;
  EXPECT_TRUE(doc["rows"].empty()) << "a glTF file has no row in the scans table: " << r.out;
  for (const char* tool : {"draco_transcoder", "gltfpack"}) {
    const auto& o = row[tool];
    if (!o["ok"].get<bool>() && !tsm_test::running_in_ci()) {
      EXPECT_NE(o["error"].get<std::string>().find("not installed"), std::string::npos) << r.out;
      continue;
    }
    ASSERT_TRUE(o["ok"].get<bool>()) << tool << ": " << r.out;
    EXPECT_GT(o["geometry_bytes"].get<size_t>(), 100u) << tool << ": " << r.out;
    EXPECT_LT(o["geometry_bytes"].get<size_t>(), o["glb_bytes"].get<size_t>()) << tool << ": " << r.out;
    EXPECT_GT(o["decode_ms"].get<double>(), 0.0) << tool << ": " << r.out;
  }

  r = tsm("bench " + quote(file("ball.glb")) + " --runs 1 -q 11 --quiet");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("| ball.glb | 642 | 1,280 | 11 |"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("| mesh | V | q |"), std::string::npos) << "no empty scans table: " << r.out;

  // --browser: the browser columns, or (web/ not set up here) a failure that says what to do.
  r = tsm("bench " + quote(file("ball.glb")) + " --runs 1 -q 11 --quiet --browser");
  EXPECT_NE(r.out.find("| tsm browser ms | draco3d browser ms | meshopt browser ms |"), std::string::npos) << r.out;
  if (r.code == 0) {
    EXPECT_EQ(r.out.find("| - | - | - |\n"), std::string::npos) << "browser figures: " << r.out;
  } else {
    EXPECT_EQ(r.code, 3) << r.out << r.err;
    EXPECT_NE(r.out.find("failed: --browser: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("bash web/test.sh"), std::string::npos) << r.out;
  }
}

// A progressive file: info lists its batches; a truncated copy fails to
// decode, except with --partial, which writes a coarser level.
TEST_F(Cli, ProgressiveEncodePartialDecodeAndInfo) {
  tsm::Mesh m = tsm_test::icosphere(5);
  ASSERT_TRUE(tsm::write_mesh(file("in.ply"), m).ok());
  ASSERT_EQ(tsm("encode " + q("in.ply") + " --progressive -o " + q("p.tsm")).code, 0);
  Result r = tsm("info " + q("p.tsm"));
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(tsm_test::contains(r.out, "refinement batches"));
  Result j = tsm("info " + q("p.tsm") + " --json");
  EXPECT_EQ(j.code, 0);
  EXPECT_TRUE(tsm_test::contains(j.out, "\"progressive\": {\"base_vertices\": "));
  EXPECT_TRUE(tsm_test::contains(j.out, "\"batches\": [{\"bytes\": "));
  const std::string bytes = slurp(file("p.tsm"));
  spit(file("cut.tsm"), bytes.substr(0, bytes.size() * 6 / 10));
  EXPECT_NE(tsm("decode " + q("cut.tsm") + " -o " + q("whole.ply")).code, 0);
  ASSERT_EQ(tsm("decode " + q("cut.tsm") + " --partial -o " + q("part.ply")).code, 0);
  tsm::Mesh part;
  ASSERT_TRUE(tsm::read_mesh(file("part.ply"), part).ok());
  EXPECT_GT(part.face_count(), 0u);
  EXPECT_LT(part.face_count(), m.face_count());
}

}  // namespace
