#include "urlab/replay/npz.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "mujoco_test.h"
#include "urlab/core/files.h"
#include "urlab/physics/model.h"

namespace urlab::replay {
namespace {

using urlab::testing::MakeTempDir;
using urlab::testing::RunCommand;
using urlab::testing::WriteTextFile;

// Prints every array of the .npz file argv[1] as "name dtype shape bits..." (sorted by name),
// after checking the zip's CRCs and that each entry is NPY 1.0 with its data 64-byte aligned.
constexpr char kDumpScript[] = R"(import sys, zipfile
import numpy as np
path = sys.argv[1]
with zipfile.ZipFile(path) as z:
    assert z.testzip() is None, 'bad CRC'
    for info in z.infolist():
        assert info.compress_type == zipfile.ZIP_STORED
        b = z.read(info.filename)
        assert b[:8] == b'\x93NUMPY\x01\x00', b[:8]
        header_len = int.from_bytes(b[8:10], 'little')
        assert (10 + header_len) % 64 == 0, header_len
        assert b[10 + header_len - 1:10 + header_len] == b'\n'
d = np.load(path, allow_pickle=False)
for k in sorted(d.files):
    a = d[k]
    bits = ' '.join('%016x' % v for v in a.reshape(-1).view('<u8').tolist())
    print(k, a.dtype.str, a.shape, bits)
)";

std::string Bits(const std::vector<double>& values) {
  std::string out;
  char buf[20];
  for (const double v : values) {
    std::snprintf(buf, sizeof buf, "%016llx",
                  static_cast<unsigned long long>(std::bit_cast<std::uint64_t>(v)));
    out += (out.empty() ? "" : " ") + std::string(buf);
  }
  return out;
}

class NpzTest : public urlab::testing::MujocoTest {
 protected:
  NpzTest() : dir_(MakeTempDir("npz")) {}

  // The dump of `path` by NumPy; skips the test when Python or NumPy is missing.
  bool Dump(const std::string& path, std::string* out) {
    if (!std::filesystem::exists("/usr/bin/python3") ||
        RunCommand("/usr/bin/python3 -c 'import numpy'") != 0) {
      return false;
    }
    const std::string script = WriteTextFile(dir_, "dump.py", kDumpScript);
    const int rc = RunCommand("/usr/bin/python3 " + script + " " + path, out);
    EXPECT_EQ(rc, 0) << *out;
    return true;
  }

  std::string dir_;
};

TEST_F(NpzTest, NumpyReadsEveryArrayExactly) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<NpyArray> arrays = {
      {"matrix", {2, 3}, {1.0 / 3, -0.0, 5e-324, 1.7976931348623157e308, -inf, nan}},
      {"vector", {5}, {0.1, 0.2, 0.3, -1e-300, 42}},
      {"scalar", {}, {2.5}},
      {"empty", {0}, {}},
      {"cube", {2, 1, 2}, {1, 2, 3, 4}},
      {"a_long_name_with.dots-and_digits_0123456789", {1}, {7}},
  };
  const std::string path = dir_ + "/arrays.npz";
  WriteNpz(path, arrays);
  std::string out;
  if (!Dump(path, &out)) GTEST_SKIP() << "/usr/bin/python3 with numpy is not installed";
  const std::string expected = "a_long_name_with.dots-and_digits_0123456789 <f8 (1,) " + Bits({7}) +
                               "\n" + "cube <f8 (2, 1, 2) " + Bits({1, 2, 3, 4}) + "\n" +
                               "empty <f8 (0,) \n" + "matrix <f8 (2, 3) " + Bits(arrays[0].data) +
                               "\n" + "scalar <f8 () " + Bits({2.5}) + "\n" + "vector <f8 (5,) " +
                               Bits(arrays[1].data) + "\n";
  EXPECT_EQ(out, expected);
}

TEST_F(NpzTest, ExportNpzWritesTimeQposQvel) {
  const physics::ModelPtr m = physics::CompileXmlString(
      ReadInputFile(urlab::testing::TestData("replay/two_arms.xml"), "test model"));
  const ModelTables tables = ModelTables::Of(m.get(), {"a", "b"});
  Trajectory traj;
  traj.nq = tables.nq;
  traj.nv = tables.nv;
  for (int r = 0; r < 3; ++r) {
    traj.time.push_back(0.002 * r);
    for (int i = 0; i < traj.nq; ++i) traj.qpos.push_back(m->qpos0[i] + 0.1 * r + 0.01 * i);
    for (int i = 0; i < traj.nv; ++i) traj.qvel.push_back(-0.5 * r + i);
  }
  const std::string path = dir_ + "/traj.npz";
  ExportNpz(path, tables, traj);
  std::string out;
  if (!Dump(path, &out)) GTEST_SKIP() << "/usr/bin/python3 with numpy is not installed";
  EXPECT_EQ(out, "qpos <f8 (3, 18) " + Bits(traj.qpos) + "\nqvel <f8 (3, 15) " + Bits(traj.qvel) +
                     "\ntime <f8 (3,) " + Bits(traj.time) + "\n");

  traj.qvel.clear();
  ExportNpz(path, tables, traj);
  ASSERT_TRUE(Dump(path, &out));
  EXPECT_EQ(out.find("qvel"), std::string::npos) << out;

  traj.qpos[3] = std::nan("");
  EXPECT_THROW(ExportNpz(dir_ + "/nan.npz", tables, traj), Error);
}

TEST_F(NpzTest, StringArraysAreUnicodeNumpyReadsWithoutPickle) {
  NpyArray names;
  names.name = "names";
  names.shape = {3};
  names.text = {"arm/shoulder",
                "h\xc3\xbc"
                "ft",
                ""};  // UTF-8 "hüft"
  names.strings = true;
  NpyArray none;  // an empty name list is still a string array
  none.name = "none";
  none.shape = {0};
  none.strings = true;
  const std::string path = dir_ + "/names.npz";
  WriteNpz(path, {names, none, {"values", {2}, {1.5, 2.5}, {}, false}});
  if (RunCommand("/usr/bin/python3 -c 'import numpy'") != 0) GTEST_SKIP() << "no numpy";
  const std::string script = WriteTextFile(dir_, "names.py", R"(import sys
import numpy as np
z = np.load(sys.argv[1], allow_pickle=False)
print(z["names"].dtype.str, z["names"].tolist() == ["arm/shoulder", "h\u00fcft", ""],
      z["none"].dtype.str, z["none"].shape, z["values"].tolist())
)");
  std::string out;
  ASSERT_EQ(RunCommand("/usr/bin/python3 " + script + " " + path, &out), 0) << out;
  EXPECT_EQ(out, "<U12 True <U1 (0,) [1.5, 2.5]\n");
  // Strings and doubles in one array, or a count the shape does not hold, are refused.
  names.data = {1};
  EXPECT_THROW(WriteNpz(dir_ + "/bad.npz", {names}), Error);
  names.data.clear();
  names.shape = {2};
  EXPECT_THROW(WriteNpz(dir_ + "/bad.npz", {names}), Error);
}

TEST_F(NpzTest, BadNamesAndShapesAreErrors) {
  const auto message = [&](const std::vector<NpyArray>& arrays) {
    try {
      WriteNpz(dir_ + "/bad.npz", arrays);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const auto contains = [](const std::string& what, const std::string& part) {
    return what.find(part) != std::string::npos;
  };
  EXPECT_TRUE(contains(message({{"", {1}, {1}}}), "empty name"));
  EXPECT_TRUE(contains(message({{"a/b", {1}, {1}}}), "'a/b' contains '/'"));
  EXPECT_TRUE(contains(message({{std::string("a\0b", 3), {1}, {1}}}), "'a\\x00b' contains"));
  EXPECT_TRUE(contains(message({{"x", {1}, {1}}, {"x", {1}, {2}}}), "two arrays are named 'x'"));
  EXPECT_TRUE(contains(message({{"x", {2, 2}, {1, 2, 3}}}), "holds 4 values but it has 3"));
  EXPECT_TRUE(contains(message({{"x", {}, {}}}), "holds 1 values but it has 0"));
  const std::size_t huge = std::numeric_limits<std::size_t>::max() / 2 + 1;
  EXPECT_TRUE(contains(message({{"x", {huge, 4}, {}}}), "overflows"));
  EXPECT_EQ(message({{"x", {huge, 0}, {}}}), "no error");  // a zero dimension: no overflow
  EXPECT_TRUE(contains(message({{"x", {huge, 0}, {1}}}), "holds 0 values but it has 1"));
  EXPECT_TRUE(contains(message({{"x", {1}, {1}}}), "no error"));
  EXPECT_TRUE(std::filesystem::exists(dir_ + "/bad.npz"));
  EXPECT_TRUE(contains(message({{"y", {2}, {1}}}), dir_ + "/bad.npz: cannot write .npz"));
}

}  // namespace
}  // namespace urlab::replay
