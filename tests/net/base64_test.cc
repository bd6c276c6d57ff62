#include "net/base64.h"

#include <gtest/gtest.h>

#include <string>

namespace urlab::net {
namespace {

TEST(Base64Test, Rfc4648Vectors) {
  const std::pair<std::string, std::string> cases[] = {{"", ""},
                                                       {"f", "Zg=="},
                                                       {"fo", "Zm8="},
                                                       {"foo", "Zm9v"},
                                                       {"foob", "Zm9vYg=="},
                                                       {"fooba", "Zm9vYmE="},
                                                       {"foobar", "Zm9vYmFy"},
                                                       {"\xff\xfe", "//4="}};
  for (const auto& [in, out] : cases) EXPECT_EQ(Base64Encode(in.data(), in.size()), out) << in;
}

Json Bytes(const std::string& s) {
  return Json::binary(std::vector<std::uint8_t>(s.begin(), s.end()));
}

TEST(Base64Test, BytesFieldsAndByteMapsAreRenamedStructuresAreNot) {
  Json reply{{"op", "x"},
             {"mjb", Bytes("foo")},
             {"vfs_assets", Json::object()},
             {"per_articulation",
              {{"arm", {{"qpos", Bytes("f")}, {"qvel", Bytes("fo")}}},
               {"leg", {{"qpos", {1.0, 2.0}}, {"sensors", {{"s", Bytes("foo")}}}}}}},
             {"list", Json::array({Bytes("foob"), 3})}};
  BinaryToBase64(reply);
  EXPECT_EQ(reply["mjb_base64"], "Zm9v");
  EXPECT_FALSE(reply.contains("mjb"));
  EXPECT_TRUE(reply["vfs_assets_base64"].is_object());  // renamed even when empty
  const Json& arm = reply["per_articulation"]["arm"];   // an all-bytes structure keeps its key
  EXPECT_EQ(arm["qpos_base64"], "Zg==");
  EXPECT_EQ(arm["qvel_base64"], "Zm8=");
  const Json& leg = reply["per_articulation"]["leg"];
  EXPECT_EQ(leg["qpos"], Json::array({1.0, 2.0}));
  EXPECT_EQ(leg["sensors_base64"]["s"], "Zm9v");
  EXPECT_EQ(reply["list"][0], "Zm9vYg==");
  // Keys keep their order.
  std::vector<std::string> keys;
  for (const auto& [k, v] : reply.items()) keys.push_back(k);
  EXPECT_EQ(keys, (std::vector<std::string>{"op", "mjb_base64", "vfs_assets_base64",
                                            "per_articulation", "list"}));
}

}  // namespace
}  // namespace urlab::net
