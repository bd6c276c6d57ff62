// Queries (urlab/ops/queries.h): get_contacts and the direct query are one extractor
// (ops::CollectContacts, which the viewer's contact drawing also captures with) with one
// validation of the filter; list_keyframes and ops::ListKeyframes are one list.
#include "urlab/ops/queries.h"

#include "ops/ops_fixture.h"

namespace urlab::ops::test {
namespace {

TEST_F(OpsTest, ContactsAreOneExtractorWithOneFilterValidation) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello();
  c.Op("reset", {{"keyframe_name", "bent"}});  // the ball rests on the floor: one contact
  const Json wire = c.Op("get_contacts", {{"filter", {{"body1", "arm_ball"}}}});
  ASSERT_EQ(wire["op"], "get_contacts_ok") << wire.dump();
  const ContactsQuery direct = QueryContacts(session(), {.body1 = "arm_ball"});
  Wait(direct.seq);
  ASSERT_EQ(wire["count"].get<std::size_t>(), direct.list->contacts.size());
  ASSERT_GE(direct.list->contacts.size(), 1u);
  const Contact& k = direct.list->contacts[0];
  EXPECT_EQ(wire["contacts"][0]["geom1_id"], k.geom1);
  EXPECT_EQ(wire["contacts"][0]["dist"], k.dist);
  EXPECT_EQ(wire["contacts"][0]["force"][0], k.force[0]);
  EXPECT_GT(k.force[0], 0.0) << "the floor pushes the ball up";
  // A limit: matched counts what the filter passed, the list holds at most the limit.
  const ContactsQuery none = QueryContacts(session(), {.max_contacts = 0});
  Wait(none.seq);
  EXPECT_TRUE(none.list->contacts.empty());
  EXPECT_EQ(none.list->matched, wire["matched"].get<int>());

  EXPECT_EQ(FromReply(c.Op("get_contacts", {{"filter", {{"body1", "ghost"}}}})),
            FromCall([&] { QueryContacts(session(), {.body1 = "ghost"}); }));
  EXPECT_EQ(FromReply(c.Op("get_contacts", {{"filter", {{"geom2", "ghost"}}}})),
            FromCall([&] { QueryContacts(session(), {.geom2 = "ghost"}); }));
  EXPECT_EQ(FromReply(c.Op("get_contacts", {{"max_contacts", -1}})),
            FromCall([&] { QueryContacts(session(), {.max_contacts = -1}); }));
}

TEST_F(OpsTest, KeyframesAreOneList) {
  Play();
  Client c(ctx_, rpc());
  c.Hello();
  const Json wire = c.Op("list_keyframes")["keyframes"];
  const std::vector<KeyframeInfo> direct = ListKeyframes(session());
  ASSERT_EQ(wire.size(), direct.size());
  ASSERT_EQ(direct.size(), 1u);
  EXPECT_EQ(wire[0]["name"], direct[0].name);
  EXPECT_EQ(direct[0].name, "bent");
  EXPECT_EQ(direct[0].articulation, "arm");
  EXPECT_EQ(wire[0]["full_name"], direct[0].full_name);
}

}  // namespace
}  // namespace urlab::ops::test
