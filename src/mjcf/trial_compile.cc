#include "mjcf/trial_compile.h"

namespace urlab::mjcf {

physics::ModelPtr TrialCompile(const std::string& xml, std::string* error) {
  return physics::TryCompileXmlString(xml, error);
}

}  // namespace urlab::mjcf
