#pragma once
// The dialect bridge's rules as data (internal to the mjcf module). Every change the bridge makes
// names one row of the rule table (`BridgeRules()` in include/urlab/mjcf/bridge.h: construct,
// kind, the passes that apply it, as functions of bridge_pass.h). Attributes that are only dropped,
// approximated or refused according to their value are handled by one generic pass driven by the
// attribute-policy table below; everything that needs computation has its own pass.
//
// Thread: immutable tables; any thread may read.
#include <span>
#include <string_view>

#include "urlab/mjcf/bridge.h"

namespace urlab::mjcf {

// The rule row of `id`; throws Error for an id that is not in the table (a programming error,
// caught by bridge_test's check that every change names a row).
const BridgeRule& FindBridgeRule(std::string_view id);

// When the `rule_if` branch of an attribute policy applies; otherwise `rule_else` does.
enum class AttributeCondition {
  kAlways,   // rule_if always
  kZero,     // every number of the value is 0
  kValueIn,  // the value is one of `values` ("a|b")
};

// One policy for 3.x attributes the bridge does not compute with: which elements (`elements`:
// space-separated tags; "<sensor>" = any element of a <sensor> section, "<actuator>" = any
// actuator element; defaults included), which attributes (space separated; "*" = any 3.x
// attribute left), the condition, the rule applied (and why) in each branch. A rule whose kind is
// dropped or approximated removes the attribute; refused removes it and refuses the document.
struct AttributePolicy {
  const char* elements;
  const char* attributes;
  AttributeCondition condition;
  const char* values;  // for kValueIn
  const char* rule_if;
  const char* why_if;
  const char* rule_else;  // nullptr with kAlways
  const char* why_else;
};

// The policies, first match wins.
std::span<const AttributePolicy> AttributePolicies();

// 3.x elements that cannot be expressed in 2.2.2: why, and the nearest 2.2.2 construct (the
// refusal message says both).
struct RefusedElement {
  const char* tag;
  const char* why;
  const char* nearest;
};
std::span<const RefusedElement> RefusedElements();

}  // namespace urlab::mjcf
