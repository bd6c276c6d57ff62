// Every file in tests/data/mjcf/broken (see its MANIFEST.tsv) goes through the full pipeline that
// `urlab compile` runs (read, write, compile with MuJoCo): each must fail with an error that names
// the expected file and line and says what is wrong; nothing may crash.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mujoco_test.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

struct BrokenCase {
  std::string file, expected_file, message;
  int line = 0;
};

std::vector<BrokenCase> LoadManifest() {
  std::vector<BrokenCase> out;
  std::ifstream in(URLAB_TEST_DATA_DIR "/mjcf/broken/MANIFEST.tsv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    BrokenCase c;
    std::string num;
    std::getline(ss, c.file, '\t');
    std::getline(ss, c.expected_file, '\t');
    std::getline(ss, num, '\t');
    std::getline(ss, c.message, '\t');
    c.line = std::stoi(num);
    out.push_back(c);
  }
  return out;
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Runs the pipeline; returns the error message and location, or nullopt when it succeeded.
std::optional<std::pair<SourceLocation, std::string>> Pipeline(const std::string& path) {
  try {
    document::Document doc = mjcf::ReadFile(path);
    // Unknown attributes are kept (and MuJoCo then rejects them): the reader's diagnostic is the
    // clearer report.
    if (!doc.diagnostics().empty()) {
      return std::make_pair(doc.diagnostics()[0].where, doc.diagnostics()[0].message);
    }
    mjcf::LineMap map;
    const std::string xml = mjcf::WriteString(doc, {}, &map);
    try {
      physics::CompileXmlString(xml);
    } catch (const physics::CompileError& e) {
      // Point at the source element MuJoCo's message names.
      const std::string msg = e.what();
      SourceLocation where{path, 0};
      if (const auto l = mjcf::CompileMessageLine(msg)) {
        if (*l > 0 && *l <= map.size() && map[*l - 1]) where = map[*l - 1]->location();
      }
      return std::make_pair(where, mjcf::ExplainCompileMessage(msg, map));
    }
  } catch (const InputError& e) {
    return std::make_pair(e.where(), std::string(e.what()));
  }
  return std::nullopt;
}

class BrokenCorpusTest : public testing::MujocoTest,
                         public ::testing::WithParamInterface<BrokenCase> {};

TEST_P(BrokenCorpusTest, FailsWithFileLineAndReason) {
  const BrokenCase& c = GetParam();
  const std::string path = URLAB_TEST_DATA_DIR "/mjcf/broken/" + c.file;
  const auto result = Pipeline(path);
  ASSERT_TRUE(result.has_value()) << c.file << " was accepted";
  const auto& [where, message] = *result;
  const std::string expected_file = URLAB_TEST_DATA_DIR "/mjcf/broken/" + c.expected_file;
  EXPECT_EQ(fs::weakly_canonical(where.file), fs::weakly_canonical(expected_file)) << message;
  if (c.line > 0) {
    EXPECT_EQ(where.line, c.line) << message;
  }
  EXPECT_NE(Lower(message).find(Lower(c.message)), std::string::npos)
      << "expected '" << c.message << "' in: " << message;
  TakeWarnings();
}

INSTANTIATE_TEST_SUITE_P(Manifest, BrokenCorpusTest, ::testing::ValuesIn(LoadManifest()),
                         [](const ::testing::TestParamInfo<BrokenCase>& p) {
                           std::string n = fs::path(p.param.file).stem().string();
                           for (char& ch : n) {
                             if (!isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return n;
                         });

}  // namespace
}  // namespace urlab
