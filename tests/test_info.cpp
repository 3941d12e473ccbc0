// The tool's `info` attribute listing and decode's STL / OFF output with the
// writers' notes on stderr, run as a separate process (TSM_CLI_PATH).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace {

namespace fs = std::filesystem;
using tsm_test::contains;

struct ToolRun {
  int code = -1;
  std::string out, err;
};

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

class ToolOutput : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(fs::is_regular_file(TSM_CLI_PATH)) << TSM_CLI_PATH; }

  ToolRun tsm(const std::string& args) {
    const std::string out = logs.file("stdout"), err = logs.file("stderr");
    const std::string cmd = quote(TSM_CLI_PATH) + " " + args + " </dev/null >" + quote(out) + " 2>" + quote(err);
    const int status = std::system(cmd.c_str());
    ToolRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }
  std::string q(const std::string& name) const { return quote(dir.file(name)); }

  // in.ply: a sphere with a float 'confidence' and an integer 'label' per vertex.
  void write_scan() {
    tsm::Mesh m = tsm_test::icosphere(3);
    tsm::Attribute conf, label;
    conf.name = "confidence";
    label.name = "label";
    label.type = tsm::AttributeType::u8;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      conf.values.push_back(static_cast<float>(v % 997) / 996.0f);
      label.values.push_back(static_cast<float>(v % 7));
    }
    m.attributes = {conf, label};
    tsm::Status s = tsm::write_mesh(dir.file("in.ply"), m);
    ASSERT_TRUE(s.ok()) << s.to_string();
  }

  tsm_test::TempDir dir, logs;
};

TEST_F(ToolOutput, InfoListsTheAttributes) {
  write_scan();
  ToolRun r = tsm("encode " + q("in.ply") + " -o " + q("a.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  r = tsm("info " + q("a.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, " attributes + ")) << r.out;
  EXPECT_TRUE(contains(r.out, "attribute  kind     domain type ")) << r.out;
  EXPECT_TRUE(contains(r.out, "bits/v  coded as")) << r.out;
  EXPECT_TRUE(contains(r.out, "confidence generic  vertex f32x1")) << r.out;
  EXPECT_TRUE(contains(r.out, "grid, 16 bits")) << r.out;  // the default --generic-bits, as the file says
  EXPECT_TRUE(contains(r.out, "label      generic  vertex u8x1")) << r.out;
  EXPECT_TRUE(contains(r.out, "  exact")) << r.out;
  r = tsm("info --json " + q("a.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "\"attributes\": [{\"name\": \"confidence\", \"kind\": \"generic\", \"domain\": "
                              "\"vertex\", \"type\": \"f32\", \"components\": 1, \"values\": 642, \"coding\": "
                              "\"grid\", \"bits\": 16, \"tables\": false, \"bytes\": "))
      << r.out;
  // Other bits are what the file says.
  r = tsm("encode " + q("in.ply") + " -o " + q("b.tsm") + " --generic-bits 11");
  ASSERT_EQ(r.code, 0) << r.err;
  r = tsm("info " + q("b.tsm"));
  EXPECT_TRUE(contains(r.out, "grid, 11 bits")) << r.out;
  // A mesh without attributes says nothing about them.
  ASSERT_TRUE(tsm::write_mesh(dir.file("plain.ply"), tsm_test::icosphere(1)).ok());
  r = tsm("encode " + q("plain.ply") + " -o " + q("plain.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  r = tsm("info " + q("plain.tsm"));
  EXPECT_TRUE(contains(r.out, " geometry + ")) << r.out;
  EXPECT_FALSE(contains(r.out, "attributes +")) << r.out;
  EXPECT_FALSE(contains(r.out, "attribute ")) << r.out;
}

// inspect() tells what each attribute's values cost: the costs add up to
// the attribute streams less their headers and tables, and a noisy
// attribute costs more than a constant one.
TEST(Inspect, AttributeBytesAddUp) {
  tsm::Mesh m = tsm_test::icosphere(4);
  tsm::Attribute noisy, constant;
  noisy.name = "noisy";
  constant.name = "constant";
  uint32_t x = 12345;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    x = x * 1664525u + 1013904223u;
    noisy.values.push_back(static_cast<float>(x >> 8) / 16777216.0f);
    constant.values.push_back(0.5f);
  }
  m.attributes = {noisy, constant};
  for (int segment_faces : {0, 1000}) {
    tsm::EncodeOptions o;
    o.segment_faces = static_cast<uint32_t>(segment_faces);
    std::string bytes;
    ASSERT_TRUE(tsm::encode(m, o, bytes).ok());
    tsm::FileInfo fi;
    ASSERT_TRUE(tsm::inspect(bytes, fi).ok());
    ASSERT_EQ(fi.attributes.size(), 2u);
    EXPECT_EQ(fi.attributes[0].name, "noisy");
    EXPECT_EQ(fi.attributes[0].coding, "grid");
    EXPECT_EQ(fi.attributes[0].bits, 16);
    const uint64_t sum = fi.attributes[0].coded_bytes + fi.attributes[1].coded_bytes;
    EXPECT_LE(sum, fi.attribute_bytes + 8 * fi.segments.size());
    EXPECT_GE(sum + 200 * fi.segments.size(), fi.attribute_bytes) << "headers cost more than expected";
    // 16 random bits per vertex cannot be coded in fewer than ~15.
    EXPECT_GT(fi.attributes[0].coded_bytes, 15 * m.vertex_count() / 8);
    EXPECT_LT(fi.attributes[1].coded_bytes, m.vertex_count() / 8);
  }
}

TEST_F(ToolOutput, DecodeWritesStlAndOffAndSaysWhatTheyDrop) {
  write_scan();
  ToolRun r = tsm("encode " + q("in.ply") + " -o " + q("a.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* name : {"x.stl", "x.off"}) {
    SCOPED_TRACE(name);
    r = tsm("decode " + q("a.tsm") + " -o " + q(name));
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string fmt = std::string(name) == "x.stl" ? "STL" : "OFF";
    EXPECT_TRUE(contains(r.err, "tsm: note: " + dir.file(name) + ": " + fmt +
                                    " cannot hold the vertex attribute 'confidence', vertex attribute 'label'"))
        << r.err;
    tsm::Mesh back;
    tsm::ReadInfo info;
    tsm::Status s = tsm::read_mesh(dir.file(name), back, {}, &info);
    ASSERT_TRUE(s.ok()) << s.to_string();
    EXPECT_EQ(back.face_count(), tsm_test::icosphere(3).face_count());
  }
  // --format and --ascii: ASCII STL.
  r = tsm("decode " + q("a.tsm") + " -o " + q("y.stl") + " --format stl --ascii --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // --quiet: no notes either
  EXPECT_EQ(slurp(dir.file("y.stl")).substr(0, 10), "solid tsm\n");
  // PLY keeps every attribute: nothing to say.
  r = tsm("decode " + q("a.tsm") + " -o " + q("y.ply"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(contains(r.err, "note")) << r.err;
  // OBJ names what it cannot hold on stderr, not only inside the file.
  r = tsm("decode " + q("a.tsm") + " -o " + q("y.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "OBJ cannot hold the vertex attribute 'confidence', vertex attribute 'label'")) << r.err;
}

TEST_F(ToolOutput, HelpAndErrorsListTheSameOutputFormats) {
  ToolRun r = tsm("decode --help");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "ply|obj|stl|off|gltf|glb")) << r.out;
  EXPECT_TRUE(contains(r.out, "PLY, OBJ, STL, OFF, glTF or GLB")) << r.out;
  write_scan();
  r = tsm("encode " + q("in.ply") + " -o " + q("a.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  r = tsm("decode " + q("a.tsm") + " -o " + q("a.xyz"));
  EXPECT_EQ(r.code, 2);  // a usage error, found before anything is decoded
  EXPECT_TRUE(contains(r.err, "end it in .ply, .obj, .stl, .off, .gltf or .glb, or pass --format "
                              "ply|obj|stl|off|gltf|glb"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir.file("a.xyz")));
}

TEST_F(ToolOutput, ObjGroupsSurviveTheTool) {
  const tsm::Mesh sphere = tsm_test::icosphere(1);
  std::ostringstream text;
  text << "mtllib scene.mtl\n";
  for (size_t v = 0; v < sphere.vertex_count(); ++v)
    text << "v " << sphere.positions[3 * v] << " " << sphere.positions[3 * v + 1] << " " << sphere.positions[3 * v + 2]
         << "\n";
  for (size_t f = 0; f < sphere.face_count(); ++f) {
    if (f == 0) text << "o body\ng front\nusemtl red\n";
    if (f == 40) text << "g back\nusemtl blue\n";
    text << "f " << sphere.face(f)[0] + 1 << " " << sphere.face(f)[1] + 1 << " " << sphere.face(f)[2] + 1 << "\n";
  }
  {
    std::ofstream f(dir.file("x.obj"));
    f << text.str();
  }
  ToolRun r = tsm("encode " + q("x.obj") + " -o " + q("x.tsm"));
  ASSERT_EQ(r.code, 0) << r.err;
  r = tsm("decode " + q("x.tsm") + " -o " + q("y.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(contains(r.err, "note")) << r.err;
  const std::string y = slurp(dir.file("y.obj"));
  for (const char* line : {"mtllib scene.mtl\n", "o body\n", "g front\n", "g back\n", "usemtl red\n", "usemtl blue\n"})
    EXPECT_TRUE(contains(y, line)) << line;
  // glTF has no face attributes: written without them, with a note.
  r = tsm("decode " + q("x.tsm") + " -o " + q("y.glb"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "glTF cannot hold the OBJ object, group, material and smoothing group of each face"))
      << r.err;
  r = tsm("info " + q("x.tsm"));
  EXPECT_TRUE(contains(r.out, "obj:group")) << r.out;
  EXPECT_TRUE(contains(r.out, "metadata: 'obj'")) << r.out;
}

}  // namespace
