#include "skin_file.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/document/document.h"

namespace urlab::mjcf::internal {

namespace {

// Sequential little-endian reads over the file's bytes; false once past the end.
class Cursor {
 public:
  explicit Cursor(const std::vector<char>& bytes) : bytes_(bytes) {}
  bool Int(int32_t& out) { return Raw(&out, sizeof out); }
  bool Float(float& out) { return Raw(&out, sizeof out); }
  bool Raw(void* out, size_t n) {
    if (bytes_.size() - pos_ < n) return false;
    std::memcpy(out, bytes_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  bool AtEnd() const { return pos_ == bytes_.size(); }

 private:
  const std::vector<char>& bytes_;
  size_t pos_ = 0;
};

bool Floats(Cursor& c, int64_t n, std::vector<double>& out) {
  out.clear();
  for (int64_t i = 0; i < n; ++i) {
    float f;
    if (!c.Float(f)) return false;
    out.push_back(static_cast<double>(f));
  }
  return true;
}

bool Ints(Cursor& c, int64_t n, std::string& out) {
  out.clear();
  for (int64_t i = 0; i < n; ++i) {
    int32_t v;
    if (!c.Int(v)) return false;
    if (i) out += ' ';
    out += std::to_string(v);
  }
  return true;
}

}  // namespace

void InlineSkinFile(document::Element& skin) {
  const std::optional<std::string> path = skin.ResolvedFile("file");
  if (!path) return;
  auto fail = [&](const std::string& what) {
    throw InputError(skin.location(), "<skin>: skin file '" + *path + "' " + what);
  };
  std::ifstream in(*path, std::ios::binary);
  if (!in) fail("cannot be read");
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  Cursor c(bytes);
  int32_t nvert = 0, ntexcoord = 0, nface = 0, nbone = 0;
  if (!c.Int(nvert) || !c.Int(ntexcoord) || !c.Int(nface) || !c.Int(nbone)) {
    fail("is shorter than its header");
  }
  if (nvert < 0 || ntexcoord < 0 || nface < 0 || nbone < 0) fail("has negative sizes");
  std::vector<double> vertex, texcoord;
  std::string face;
  if (!Floats(c, 3 * int64_t{nvert}, vertex) || !Floats(c, 2 * int64_t{ntexcoord}, texcoord) ||
      !Ints(c, 3 * int64_t{nface}, face)) {
    fail("is shorter than its header says");
  }
  struct Bone {
    std::string body;
    std::vector<double> bindpos, bindquat, weights;
    std::string ids;
  };
  std::vector<Bone> bones;
  for (int32_t b = 0; b < nbone; ++b) {
    Bone bone;
    char name[41] = {};
    int32_t count = 0;
    if (!c.Raw(name, 40) || !Floats(c, 3, bone.bindpos) || !Floats(c, 4, bone.bindquat) ||
        !c.Int(count) || count < 0 || !Ints(c, count, bone.ids) ||
        !Floats(c, count, bone.weights)) {
      fail("is shorter than its header says (bone " + std::to_string(b) + ")");
    }
    bone.body = name;  // 0-terminated; characters after the first 0 are ignored
    bones.push_back(std::move(bone));
  }
  if (!c.AtEnd()) fail("is longer than its header says");

  const std::string name = document::DefinedName(skin);
  skin.Unset("file");
  if (!name.empty()) skin.Set("name", name);
  if (!vertex.empty()) skin.SetReals("vertex", vertex);
  if (!texcoord.empty()) skin.SetReals("texcoord", texcoord);
  if (!face.empty()) skin.Set("face", face);
  for (const Bone& b : bones) {
    document::Element& bone = skin.AddChild("bone");
    bone.set_location(skin.location());
    bone.Set("body", b.body);
    bone.SetReals("bindpos", b.bindpos);
    bone.SetReals("bindquat", b.bindquat);
    bone.Set("vertid", b.ids);
    bone.SetReals("vertweight", b.weights);
  }
}

}  // namespace urlab::mjcf::internal
