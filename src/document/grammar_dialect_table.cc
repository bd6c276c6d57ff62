// MJCF written for MuJoCo 3.x: elements and attributes the dialect bridge (mjcf/bridge.h)
// accepts and translates. Row format as in grammar_table.cc; ids starting with '+' extend the
// 2.2.2 row of that id. See grammar.h.
#include "urlab/document/grammar.h"

namespace urlab::document {

namespace {
constexpr GrammarRow kRows[] = {
    {"+mujoco", "", "", "", ""},
};
}  // namespace

std::span<const GrammarRow> DialectGrammarTable() { return kRows; }

}  // namespace urlab::document
