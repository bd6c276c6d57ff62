#pragma once
// CLI11 validators the commands share. Thread: main (argument parsing).
#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

namespace urlab::app {

// A number that must be finite and > 0 (CLI::PositiveNumber lets NaN and inf through).
inline const CLI::Validator kFinitePositive(
    [](std::string& text) -> std::string {
      double v = 0;
      std::size_t used = 0;
      try {
        v = std::stod(text, &used);
      } catch (const std::exception&) {
        return "'" + text + "' is not a number";
      }
      if (used != text.size()) return "'" + text + "' is not a number";
      if (!std::isfinite(v) || v <= 0) return "must be a finite number > 0, not " + text;
      return {};
    },
    "FINITE > 0");

}  // namespace urlab::app
