// The MJCF grammar of MuJoCo 2.2.2 (see grammar.h for the row format).
// PLACEHOLDER: being filled in from the 2.2.2 XML reference.
#include "urlab/document/grammar.h"

namespace urlab::document {

namespace {
constexpr GrammarRow kRows[] = {
    {"mujoco", "mujoco", "", "", "model:s"},
};
}  // namespace

std::span<const GrammarRow> GrammarTable() { return kRows; }

}  // namespace urlab::document
