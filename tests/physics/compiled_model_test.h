#pragma once
// A test fixture holding one compiled model and its data: subclasses name the MJCF text.
#include "mujoco_test.h"
#include "urlab/physics/model.h"

namespace urlab::testing {

class CompiledModelTest : public MujocoTest {
 protected:
  virtual const char* Xml() const = 0;
  void SetUp() override {
    model_ = physics::CompileXmlString(Xml());
    data_ = physics::MakeData(model_.get());
  }
  physics::ModelPtr model_;
  physics::DataPtr data_;
};

}  // namespace urlab::testing
