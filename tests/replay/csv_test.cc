#include "urlab/replay/csv.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <sstream>

#include "mujoco_test.h"
#include "urlab/core/files.h"
#include "urlab/physics/model.h"

namespace urlab::replay {
namespace {

using urlab::testing::MakeTempDir;
using urlab::testing::WriteTextFile;

// Every value of a and b has the same bits.
void ExpectSameBits(const std::vector<double>& a, const std::vector<double>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  if (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0) return;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::memcmp(&a[i], &b[i], sizeof(double)) != 0) {
      ADD_FAILURE() << what << "[" << i << "]: " << a[i] << " != " << b[i];
      return;
    }
  }
}

void ExpectSameTrajectory(const Trajectory& a, const Trajectory& b) {
  EXPECT_EQ(a.nq, b.nq);
  EXPECT_EQ(a.nv, b.nv);
  ExpectSameBits(a.time, b.time, "time");
  ExpectSameBits(a.qpos, b.qpos, "qpos");
  ExpectSameBits(a.qvel, b.qvel, "qvel");
}

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t at = s.find(sep, start);
    out.push_back(s.substr(start, at - start));
    if (at == std::string::npos) return out;
    start = at + 1;
  }
}

class CsvTest : public urlab::testing::MujocoTest {
 protected:
  CsvTest()
      : model_(physics::CompileXmlString(
            ReadInputFile(urlab::testing::TestData("replay/two_arms.xml"), "test model"))),
        tables_(ModelTables::Of(model_.get(), {"a", "b"})),
        qpos0_(model_->qpos0, model_->qpos0 + model_->nq),
        dir_(MakeTempDir("csv")) {}

  std::string Write(const std::string& name, const std::string& text) {
    return WriteTextFile(dir_, name, text);
  }

  // A trajectory with random values (unit quaternions) and some awkward doubles.
  Trajectory Random(std::size_t rows, bool velocities, unsigned seed = 1) const {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> step(1e-4, 1e-2), value(-3, 3);
    std::normal_distribution<double> gauss;
    Trajectory t;
    t.nq = tables_.nq;
    t.nv = tables_.nv;
    double time = value(rng);
    for (std::size_t r = 0; r < rows; ++r) {
      t.time.push_back(time);
      time += step(rng);
      const std::size_t at = t.qpos.size();
      t.qpos.resize(at + static_cast<std::size_t>(t.nq));
      double* q = &t.qpos[at];
      for (int i = 0; i < t.nq; ++i) q[i] = value(rng);
      for (const JointEntry& j : tables_.joints) {
        if (j.type != mjJNT_FREE && j.type != mjJNT_BALL) continue;
        double* w = q + j.qposadr + (j.type == mjJNT_FREE ? 3 : 0);
        for (int i = 0; i < 4; ++i) w[i] = gauss(rng);
        const double n = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + w[3] * w[3]);
        for (int i = 0; i < 4; ++i) w[i] /= n;
      }
      if (velocities) {
        for (int i = 0; i < t.nv; ++i) t.qvel.push_back(10 * gauss(rng));
      }
    }
    if (rows >= 2) {
      t.qpos[static_cast<std::size_t>(Joint("a_elbow").qposadr)] = 5e-324;  // subnormal
      t.qpos[static_cast<std::size_t>(Joint("b_elbow").qposadr)] = -0.0;
      t.qpos[static_cast<std::size_t>(Joint("b_knee").qposadr)] = 1.7976931348623157e308;
      double* q1 = &t.qpos[static_cast<std::size_t>(t.nq)];
      q1[Joint("a_elbow").qposadr] = 0.1;
      q1[Joint("b_elbow").qposadr] = 1.0 / 3;
      q1[Joint("b_knee").qposadr] = -2.2250738585072014e-308;
      t.time[1] = t.time[0] + 1e-9;
    }
    return t;
  }

  const JointEntry& Joint(const char* name) const { return *tables_.FindJoint(name); }

  // The message of the InputError importing `text` raises, checked to start with "path:line: ".
  std::string ImportError(const std::string& name, const std::string& text, int line) {
    const std::string path = Write(name + ".csv", text);
    try {
      ImportCsv(path, tables_, qpos0_, nullptr);
    } catch (const InputError& e) {
      const std::string what = e.what();
      const std::string where = path + ":" + std::to_string(line) + ": ";
      EXPECT_EQ(what.substr(0, where.size()), where) << name << ": " << what;
      EXPECT_EQ(what.find('\r'), std::string::npos) << name;
      return what;
    }
    ADD_FAILURE() << name << ": no InputError";
    return "";
  }

  physics::ModelPtr model_;
  ModelTables tables_;
  std::vector<double> qpos0_;
  std::string dir_;
};

TEST_F(CsvTest, ExportThenImportIsBitForBit) {
  const Trajectory traj = Random(50, true);
  for (const bool short_names : {false, true}) {
    const std::string path = dir_ + "/round" + (short_names ? "_short" : "") + ".csv";
    ExportCsv(path, tables_, traj, {.short_names = short_names, .velocities = true});
    CsvImportReport report;
    const Trajectory back = ImportCsv(path, tables_, qpos0_, &report);
    ExpectSameTrajectory(back, traj);
    EXPECT_EQ(report.unmatched_columns, std::vector<std::string>{});
    EXPECT_EQ(report.ambiguous_columns, std::vector<std::string>{});
    EXPECT_EQ(report.unmatched_joints, std::vector<std::string>{});
    EXPECT_EQ(report.joints_without_velocity, std::vector<std::string>{});
  }
  // Without velocities: no qvel comes back.
  const std::string path = dir_ + "/no_qvel.csv";
  ExportCsv(path, tables_, traj, {.velocities = false});
  const Trajectory back = ImportCsv(path, tables_, qpos0_, nullptr);
  EXPECT_TRUE(back.qvel.empty());
  ExpectSameBits(back.qpos, traj.qpos, "qpos");
}

TEST_F(CsvTest, ExportHeaderNamesEveryValue) {
  Trajectory traj = Random(2, true);
  const std::string path = dir_ + "/header.csv";
  ExportCsv(path, tables_, traj, {.short_names = true, .velocities = true});
  const std::string text = ReadInputFile(path, "csv");
  const std::string header = text.substr(0, text.find('\n'));
  EXPECT_EQ(header,
            "time,root[0],root[1],root[2],root[3],root[4],root[5],root[6],a_elbow,wrist[0],"
            "wrist[1],wrist[2],wrist[3],b_elbow,ball[0],ball[1],ball[2],ball[3],knee,"
            "root.v[0],root.v[1],root.v[2],root.v[3],root.v[4],root.v[5],a_elbow.v,wrist.v[0],"
            "wrist.v[1],wrist.v[2],b_elbow.v,ball.v[0],ball.v[1],ball.v[2],knee.v");
  // Shortest round-trip numbers.
  const std::vector<std::string> row = Split(Split(text, '\n')[1], ',');
  EXPECT_EQ(row[8], "5e-324");
  EXPECT_EQ(row[13], "-0");
  EXPECT_EQ(row[18], "1.7976931348623157e+308");

  ExportCsv(path, tables_, traj, {});
  EXPECT_EQ(ReadInputFile(path, "csv").substr(0, 16), "time,a_root[0],a");
}

TEST_F(CsvTest, ShuffledColumnsShortNamesQuotesAndCrlfImportTheSame) {
  const Trajectory traj = Random(20, true, 3);
  const std::string path = dir_ + "/ordered.csv";
  ExportCsv(path, tables_, traj, {});
  std::vector<std::vector<std::string>> cells;
  for (const std::string& line : Split(ReadInputFile(path, "csv"), '\n')) {
    if (!line.empty()) cells.push_back(Split(line, ','));
  }
  std::vector<std::size_t> order(cells[0].size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937(5));
  std::string text = "\xEF\xBB\xBF";
  for (std::size_t r = 0; r < cells.size(); ++r) {
    for (std::size_t i = 0; i < order.size(); ++i) {
      std::string cell = cells[r][order[i]];
      if (r == 0) {
        // Short names where they are unambiguous ("elbow" is not); some quoted.
        if ((cell.starts_with("a_") || cell.starts_with("b_")) && !cell.starts_with("a_elbow") &&
            !cell.starts_with("b_elbow")) {
          cell = cell.substr(2);
        }
        if (i % 2 == 0) cell = "\"" + cell + "\"";
      }
      text += (i ? "," : "") + std::string(i % 3 == 0 ? " " : "") + cell +
              std::string(i % 4 == 0 ? "\t" : "");
    }
    text += "\r\n";
  }
  text += "\r\n \r\n";
  CsvImportReport report;
  const Trajectory back = ImportCsv(Write("shuffled.csv", text), tables_, qpos0_, &report);
  ExpectSameTrajectory(back, traj);
  EXPECT_TRUE(report.unmatched_columns.empty());
  EXPECT_TRUE(report.unmatched_joints.empty());
}

TEST_F(CsvTest, UnmatchedAndAmbiguousColumnsAndJointsAreReported) {
  std::vector<double> qpos0(18);
  for (std::size_t i = 0; i < qpos0.size(); ++i) qpos0[i] = 100.0 + static_cast<double>(i);
  const std::string text =
      "time,a_root[0],a_root[1],a_root[2],a_root[3],a_root[4],a_root[5],a_root[6],a_elbw,"
      "a_wrist[4],elbow,b_knee,,notes\n"
      "0,1,2,3,1,0,0,0,9,9,9,0.5,,hello\n"
      "1,1,2,3,0,1,0,0,9,9,9,0.25,,world\n";
  CsvImportReport report;
  const Trajectory t = ImportCsv(Write("unmatched.csv", text), tables_, qpos0, &report);
  EXPECT_EQ(report.unmatched_columns,
            (std::vector<std::string>{"a_elbw", "a_wrist[4]", "(column 13)", "notes"}));
  EXPECT_EQ(report.ambiguous_columns, std::vector<std::string>{"elbow"});
  EXPECT_EQ(report.unmatched_joints,
            (std::vector<std::string>{"a_elbow", "a_wrist", "b_elbow", "b_ball"}));
  EXPECT_TRUE(report.joints_without_velocity.empty());
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_TRUE(t.qvel.empty());
  const double* row1 = t.qpos_row(1);
  EXPECT_EQ(row1[0], 1);
  EXPECT_EQ(row1[4], 1);  // the quaternion's x
  EXPECT_EQ(row1[Joint("b_knee").qposadr], 0.25);
  for (const char* from_qpos0 : {"a_elbow", "b_elbow"}) {
    const int adr = Joint(from_qpos0).qposadr;
    EXPECT_EQ(row1[adr], 100 + adr) << from_qpos0;
  }
  const int ball = Joint("b_ball").qposadr;
  for (int i = 0; i < 4; ++i) EXPECT_EQ(row1[ball + i], 100 + ball + i);  // untouched
}

TEST_F(CsvTest, VelocityColumnsAreOptional) {
  const std::string text =
      "time,knee,knee.v,root.v[0],root.v[1],root.v[2],root.v[3],root.v[4],root.v[5]\n"
      "0,1,2,3,4,5,6,7,8\n";
  CsvImportReport report;
  const Trajectory t = ImportCsv(Write("vel.csv", text), tables_, qpos0_, &report);
  ASSERT_EQ(t.qvel.size(), 15u);
  EXPECT_EQ(t.qvel[static_cast<std::size_t>(Joint("b_knee").dofadr)], 2);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(t.qvel[static_cast<std::size_t>(i)], 3 + i);
  EXPECT_EQ(t.qvel[static_cast<std::size_t>(Joint("b_ball").dofadr)], 0);
  EXPECT_EQ(report.joints_without_velocity,
            (std::vector<std::string>{"a_elbow", "a_wrist", "b_elbow", "b_ball"}));
  EXPECT_EQ(report.unmatched_joints,
            (std::vector<std::string>{"a_root", "a_elbow", "a_wrist", "b_elbow", "b_ball"}));
}

TEST_F(CsvTest, RobustParsing) {
  const std::string text =
      "\xEF\xBB\xBF \"time\" ,\t\"b_knee\" , \"say \"\"hi\"\", all\"\r\n"
      " 0 , +1.5 ,x\r\n"
      "\"0.5\",-2e-3,y\r\n"
      "\r\n \r\n";
  CsvImportReport report;
  const Trajectory t = ImportCsv(Write("robust.csv", text), tables_, qpos0_, &report);
  EXPECT_EQ(t.time, (std::vector<double>{0, 0.5}));
  const int knee = Joint("b_knee").qposadr;
  EXPECT_EQ(t.qpos_row(0)[knee], 1.5);
  EXPECT_EQ(t.qpos_row(1)[knee], -2e-3);
  EXPECT_EQ(report.unmatched_columns, std::vector<std::string>{"say \"hi\", all"});
}

TEST_F(CsvTest, QuaternionsAreNormalised) {
  const std::string text =
      "time,b_ball[0],b_ball[1],b_ball[2],b_ball[3]\n"
      "0,2,0,0,0\n"
      "1,0,3,0,4\n";
  const Trajectory t = ImportCsv(Write("quat.csv", text), tables_, qpos0_, nullptr);
  const int ball = Joint("b_ball").qposadr;
  const double* q0 = t.qpos_row(0) + ball;
  const double* q1 = t.qpos_row(1) + ball;
  EXPECT_EQ(std::vector<double>(q0, q0 + 4), (std::vector<double>{1, 0, 0, 0}));
  EXPECT_NEAR(q1[1], 0.6, 1e-16);
  EXPECT_NEAR(q1[3], 0.8, 1e-16);
}

struct BadCsv {
  std::string name;
  std::string text;
  int line;
  std::vector<std::string> parts;  // the message contains each
};

TEST_F(CsvTest, MalformedInputIsALocatedInputError) {
  const std::vector<BadCsv> cases = {
      {"missing_time", "a_elbow,b_knee\n1,2\n", 1, {"no 'time' column"}},
      {"two_times", "time,b_knee,time\n0,1,2\n", 1, {"two time columns: 1 and 3"}},
      {"non_numeric", "time,b_knee\n0,1\n0.1,abc\n", 3, {"column 2 'b_knee'", "'abc' is not a"}},
      {"empty_cell", "time,b_knee\n0,\n", 2, {"column 2 'b_knee'", "'' is not a number"}},
      {"trailing_text", "time,b_knee\n0,1.5x\n", 2, {"'1.5x' is not a number"}},
      {"nan", "time,b_knee\n0,NaN\n", 2, {"column 2 'b_knee'", "'NaN' is not a finite number"}},
      {"inf", "time,b_knee\n-inf,1\n", 2, {"column 1 'time'", "'-inf' is not a finite number"}},
      {"overflow", "time,b_knee\n0,1e999\n", 2, {"'1e999' is out of the range of a double"}},
      {"too_few", "time,b_knee,b_elbow\n0,1\n", 2, {"the row has 2 cells, the header 3"}},
      {"too_many", "time,b_knee\n0,1\n0.5,1,2\n", 3, {"the row has 3 cells, the header 2"}},
      {"partial",
       "time,b_ball[0],b_ball[2]\n0,1,0\n",
       1,
       {"joint b_ball has 2 of its 4 qpos columns; missing: b_ball[1], b_ball[3]"}},
      {"partial_short", "time,ball[1]\n0,1\n", 1, {"missing: ball[0], ball[2], ball[3]"}},
      {"partial_velocity",
       "time,b_ball.v[0]\n0,1\n",
       1,
       {"b_ball has 1 of its 3 qvel columns; missing: b_ball.v[1], b_ball.v[2]"}},
      {"duplicate",
       "time,knee,b_knee\n0,1,2\n",
       1,
       {"column 2 'knee' and column 3 'b_knee' both give the value of joint b_knee"}},
      {"duplicate_indexed",
       "time,root[3],a_root[3]\n0,1,2\n",
       1,
       {"column 2 'root[3]' and column 3 'a_root[3]' both give value 3 of joint a_root"}},
      {"no_index",
       "time,a_root\n0,1\n",
       1,
       {"column 2 'a_root': a_root is a free joint with 7 qpos values; name its columns "
        "a_root[0] .. a_root[6]"}},
      {"equal_time",
       "time,b_knee\n0,1\n0.5,1\n0.5,2\n",
       4,
       {"time 0.5 is not after the previous row's 0.5"}},
      {"decreasing_time", "time,b_knee\n1,1\n0.5,1\n", 3, {"time 0.5 is not after"}},
      {"zero_quaternion",
       "time,b_ball[3],b_ball[0],b_ball[1],b_ball[2]\n0,0,1,0,0\n1,0,0,0,0\n",
       3,
       {"joint b_ball (column 3 'b_ball[0]', column 4 'b_ball[1]', column 5 'b_ball[2]', "
        "column 2 'b_ball[3]'): the quaternion (w x y z) is zero"}},
      {"empty", "", 1, {"empty CSV file"}},
      {"blank", "\r\n \n", 1, {"empty CSV file"}},
      {"header_only", "time,b_knee\n", 1, {"a header but no data rows"}},
      {"header_only_crlf", "time,b_knee\r\n\r\n", 1, {"a header but no data rows"}},
      {"crlf", "time,b_knee\r\n0,1\r\n0.1,x\r\n", 3, {"column 2 'b_knee': 'x' is not a number"}},
      {"blank_inside", "time,b_knee\n0,1\n\n1,2\n", 3, {"blank line inside the data (line 4"}},
      {"open_quote", "time,\"b_knee\n0,1\n", 1, {"column 2: no closing double quote"}},
      {"after_quote", "time,\"b\"x\n0,1\n", 1, {"text after the closing double quote"}},
      {"blank_first", "\ntime,b_knee\n0,1\n", 1, {"the first line is blank"}},
  };
  for (const BadCsv& c : cases) {
    const std::string what = ImportError(c.name, c.text, c.line);
    for (const std::string& part : c.parts) {
      EXPECT_NE(what.find(part), std::string::npos) << c.name << ": " << what;
    }
  }
}

TEST_F(CsvTest, MissingFileAndBadQpos0) {
  try {
    ImportCsv(dir_ + "/missing.csv", tables_, qpos0_, nullptr);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos) << e.what();
  }
  const std::string path = Write("ok.csv", "time,b_knee\n0,1\n");
  EXPECT_THROW(ImportCsv(path, tables_, std::vector<double>(3), nullptr), Error);
}

TEST_F(CsvTest, ExportRefusesABadTrajectory) {
  Trajectory traj = Random(3, false);
  const std::string path = dir_ + "/bad.csv";
  traj.qpos[4] = std::nan("");
  EXPECT_THROW(ExportCsv(path, tables_, traj), Error);
  traj.qpos[4] = 0;
  traj.time[2] = traj.time[1];
  EXPECT_THROW(ExportCsv(path, tables_, traj), Error);
  traj.time[2] = traj.time[1] + 1;
  traj.qpos.pop_back();
  EXPECT_THROW(ExportCsv(path, tables_, traj), Error);
  EXPECT_FALSE(std::filesystem::exists(path));
}

// 100,000 rows of 40 columns (time, 18 qpos, 15 qvel, 6 unmatched).
TEST_F(CsvTest, LargeImport) {
  const Trajectory traj = Random(100000, true, 9);
  const std::string path = dir_ + "/large.csv";
  ExportCsv(path, tables_, traj);
  const std::string exported = ReadInputFile(path, "csv", {}, kMaxCsvBytes);
  std::string text;
  text.reserve(exported.size() + 100000 * 20);
  std::size_t start = 0;
  for (std::size_t row = 0; start < exported.size(); ++row) {
    const std::size_t nl = exported.find('\n', start);
    text.append(exported, start, nl - start);
    text += row == 0 ? ",x1,x2,x3,x4,x5,x6\n" : ",1,2,3,4,5,6\n";
    start = nl + 1;
  }
  const std::string large = Write("large40.csv", text);
  CsvImportReport report;
  const auto start_time = std::chrono::steady_clock::now();
  const Trajectory back = ImportCsv(large, tables_, qpos0_, &report);
  // Recorded, not checked: timing depends on the machine and the build.
  RecordProperty("import_ms",
                 static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                      std::chrono::steady_clock::now() - start_time)
                                      .count()));
  ASSERT_EQ(back.rows(), 100000u);
  ExpectSameTrajectory(back, traj);
  EXPECT_EQ(report.unmatched_columns.size(), 6u);
}

}  // namespace
}  // namespace urlab::replay
