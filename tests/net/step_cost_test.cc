// StepCostEstimate (net/step_cost.h): the I/O thread's estimate of a step's cost, which decides
// whether it steps a lockstep window itself.
#include "net/step_cost.h"

#include <gtest/gtest.h>

namespace urlab::net {
namespace {

constexpr double kBudget = 2e-3;  // kMaxStepHere's 2 ms

TEST(StepCostEstimate, OnlyOneStepIsTriedBeforeAnyMeasurement) {
  StepCostEstimate e;
  EXPECT_TRUE(e.Affordable(1, kBudget));
  EXPECT_FALSE(e.Affordable(10, kBudget));
  e.Measured(40e-6);
  EXPECT_TRUE(e.Affordable(10, kBudget));
  EXPECT_FALSE(e.Affordable(100, kBudget));
}

TEST(StepCostEstimate, OneWindowSlowedByPreemptionDoesNotHandEveryLaterWindowAway) {
  StepCostEstimate e;
  for (int i = 0; i < 20; ++i) e.Measured(40e-6);
  // One window of 10 steps took 10 ms (the thread lost its core): 1 ms per step measured.
  e.Measured(1e-3);
  // The plain average would now say 232 us per step, and 10 steps would never fit again.
  EXPECT_LT(e.seconds(), 0.2 * 1e-3 + 0.8 * 40e-6);
  int tried = 0;
  for (int i = 0; i < 50; ++i) {
    if (e.Affordable(10, kBudget)) {
      ++tried;
      e.Measured(40e-6);
    }
  }
  EXPECT_GE(tried, 45);
}

TEST(StepCostEstimate, ADearerStepIsLearnedAndDeclinedSizesAreRetriedButNeverBeyondTheCheapest) {
  StepCostEstimate e;
  e.Measured(40e-6);
  for (int i = 0; i < 10; ++i) e.Measured(400e-6);  // the scene really got ten times dearer
  EXPECT_GT(e.seconds(), 300e-6);
  // Declined windows of 10 steps are retried now and then (each retry measures again).
  int tried = 0;
  for (int i = 0; i < 200; ++i) {
    if (e.Affordable(10, kBudget)) {
      ++tried;
      e.Measured(400e-6);
    }
  }
  EXPECT_GT(tried, 0);
  EXPECT_LT(tried, 40);
  // A window too long even at the cheapest step ever measured is never tried.
  for (int i = 0; i < 1000; ++i) EXPECT_FALSE(e.Affordable(100, kBudget));
}

}  // namespace
}  // namespace urlab::net
