// The diagnostics sink: collects located findings; loading throws the first error with
// "(and N more)".
#include "urlab/core/diagnostics.h"

#include <gtest/gtest.h>

namespace urlab {
namespace {

TEST(DiagnosticsTest, CollectsInOrderAndCountsErrors) {
  Diagnostics d;
  EXPECT_TRUE(d.empty());
  d.Warning({"a.xml", 3}, "first warning");
  d.Error({"a.xml", 7}, "first error");
  d.Error({"b.yaml", 2}, "second error");
  d.Add(InputError({"c.xml", 9}, "thrown"), "art: ");
  ASSERT_EQ(d.all().size(), 4u);
  EXPECT_EQ(d.error_count(), 3u);
  EXPECT_EQ(d.warnings().size(), 1u);
  EXPECT_EQ(d.errors()[2].str(), "c.xml:9: art: thrown");
  EXPECT_EQ(d.all()[0].str(), "a.xml:3: first warning");
  EXPECT_STREQ(SeverityName(d.all()[0].severity), "warning");
}

TEST(DiagnosticsTest, ThrowIfErrorsThrowsTheFirstWithTheCountOfTheRest) {
  Diagnostics d;
  d.Warning({"a.xml", 1}, "only a warning");
  EXPECT_NO_THROW(d.ThrowIfErrors());
  d.Error({"a.xml", 7}, "first error");
  try {
    d.ThrowIfErrors();
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "a.xml:7: first error");
    EXPECT_EQ(e.where().line, 7);
  }
  d.Error({"b.yaml", 2}, "second");
  d.Error({}, "third, unlocated");
  try {
    d.ThrowIfErrors();
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "a.xml:7: first error (and 2 more problem(s))");
  }
}

TEST(DiagnosticsTest, AppendLabelsEveryMessage) {
  std::vector<Diagnostic> found = {{Diagnostic::Severity::kWarning, {"m.xml", 4}, "kept"},
                                   {Diagnostic::Severity::kError, {"m.xml", 5}, "bad"}};
  Diagnostics d;
  d.Append(found, "left: ");
  EXPECT_EQ(d.all()[0].message, "left: kept");
  EXPECT_EQ(d.errors().at(0).str(), "m.xml:5: left: bad");
}

}  // namespace
}  // namespace urlab
