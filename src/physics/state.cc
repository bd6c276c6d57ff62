#include "urlab/physics/state.h"

#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/gcc_workarounds.h"

namespace urlab::physics {

static_assert(std::is_same_v<mjtNum, double>, "URLab expects MuJoCo built with double mjtNum");
static_assert(std::endian::native == std::endian::little, "state format assumes little-endian");

namespace {

constexpr char kMagic[4] = {'U', 'R', 'L', 'S'};
// magic + version + header size + 10 layout ints + time + payload size.
constexpr std::size_t kHeaderSize = 4 + 4 + 4 + 10 * 4 + 8 + 8;
constexpr std::size_t kChecksumSize = 8;
// Guards against absurd layouts in corrupt headers before any allocation happens.
constexpr std::int64_t kMaxArrayLength = std::int64_t{1} << 28;

std::uint64_t Fnv1a(const std::uint8_t* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

// The arrays of a state in serialisation order with their expected lengths and MuJoCo's state
// component.
template <typename State>
auto Arrays(State& s) {
  const StateLayout& l = s.layout;
  using Vec =
      std::conditional_t<std::is_const_v<State>, const std::vector<mjtNum>, std::vector<mjtNum>>;
  struct ArrayEntry {
    const char* name;
    Vec* vec;
    std::int64_t length;
    int component;  // mjtState
  };
  return std::array<ArrayEntry, 13>{{
      {"qpos", &s.qpos, l.nq, mjSTATE_QPOS},
      {"qvel", &s.qvel, l.nv, mjSTATE_QVEL},
      {"act", &s.act, l.na, mjSTATE_ACT},
      {"qacc_warmstart", &s.qacc_warmstart, l.nv, mjSTATE_WARMSTART},
      {"ctrl", &s.ctrl, l.nu, mjSTATE_CTRL},
      {"qfrc_applied", &s.qfrc_applied, l.nv, mjSTATE_QFRC_APPLIED},
      {"xfrc_applied", &s.xfrc_applied, std::int64_t{6} * l.nbody, mjSTATE_XFRC_APPLIED},
      {"mocap_pos", &s.mocap_pos, std::int64_t{3} * l.nmocap, mjSTATE_MOCAP_POS},
      {"mocap_quat", &s.mocap_quat, std::int64_t{4} * l.nmocap, mjSTATE_MOCAP_QUAT},
      {"userdata", &s.userdata, l.nuserdata, mjSTATE_USERDATA},
      {"history", &s.history, l.nhistory, mjSTATE_HISTORY},
      {"eq_active", &s.eq_active, l.neq, mjSTATE_EQ_ACTIVE},
      {"plugin_state", &s.plugin_state, l.npluginstate, mjSTATE_PLUGIN},
  }};
}

void Put(std::vector<std::uint8_t>* out, const void* p, std::size_t n) {
  const auto* b = static_cast<const std::uint8_t*>(p);
  // -O3: a false -Wstringop-overflow for bytes inserted into reserve()d storage (GCC PR 107852).
  URLAB_GCC_IGNORE("-Wstringop-overflow")
  out->insert(out->end(), b, b + n);
  URLAB_GCC_RESTORE
}

class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  template <typename T>
  T Get(const char* what) {
    T v;
    Need(sizeof(T), what);
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  void GetArray(std::vector<mjtNum>* v, std::int64_t n, const char* what) {
    Need(static_cast<std::size_t>(n) * sizeof(mjtNum), what);
    v->resize(static_cast<std::size_t>(n));
    if (n) std::memcpy(v->data(), bytes_.data() + pos_, v->size() * sizeof(mjtNum));
    pos_ += v->size() * sizeof(mjtNum);
  }
  std::size_t pos() const { return pos_; }

 private:
  void Need(std::size_t n, const char* what) {
    if (bytes_.size() - pos_ < n) {
      throw StateError(std::string("state data truncated while reading ") + what + " (" +
                       std::to_string(bytes_.size()) + " bytes in total)");
    }
  }
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

}  // namespace

StateLayout StateLayout::Of(const mjModel* m) {
  StateLayout l;
  l.nq = static_cast<int>(m->nq);
  l.nv = static_cast<int>(m->nv);
  l.na = static_cast<int>(m->na);
  l.nu = static_cast<int>(m->nu);
  l.nbody = static_cast<int>(m->nbody);
  l.nmocap = static_cast<int>(m->nmocap);
  l.nuserdata = static_cast<int>(m->nuserdata);
  l.nhistory = mj_stateSize(m, mjSTATE_HISTORY);
  l.neq = static_cast<int>(m->neq);
  l.npluginstate = static_cast<int>(m->npluginstate);
  return l;
}

std::string StateLayout::str() const {
  return "nq=" + std::to_string(nq) + " nv=" + std::to_string(nv) + " na=" + std::to_string(na) +
         " nu=" + std::to_string(nu) + " nbody=" + std::to_string(nbody) +
         " nmocap=" + std::to_string(nmocap) + " nuserdata=" + std::to_string(nuserdata) +
         " nhistory=" + std::to_string(nhistory) + " neq=" + std::to_string(neq) +
         " npluginstate=" + std::to_string(npluginstate);
}

bool PhysicsState::BitwiseEquals(const PhysicsState& other) const {
  if (!(layout == other.layout)) return false;
  if (std::memcmp(&time, &other.time, sizeof(time)) != 0) return false;
  const auto a = Arrays(*this);
  const auto b = Arrays(other);
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].vec->size() != b[i].vec->size()) return false;
    if (!a[i].vec->empty() &&
        std::memcmp(a[i].vec->data(), b[i].vec->data(), a[i].vec->size() * sizeof(mjtNum)) != 0) {
      return false;
    }
  }
  return true;
}

bool PhysicsState::IsConsistent() const {
  for (const auto& e : Arrays(*this)) {
    if (static_cast<std::int64_t>(e.vec->size()) != e.length) return false;
  }
  return true;
}

PhysicsState CaptureState(const mjModel* m, const mjData* d) {
  PhysicsState s;
  s.layout = StateLayout::Of(m);
  s.time = d->time;
  for (auto& e : Arrays(s)) {
    e.vec->resize(static_cast<std::size_t>(e.length));
    if (e.length) mj_getState(m, d, e.vec->data(), e.component);
  }
  return s;
}

void ApplyState(const mjModel* m, mjData* d, const PhysicsState& state) {
  const StateLayout expected = StateLayout::Of(m);
  if (!(state.layout == expected)) {
    throw StateError("state does not match the model: state has " + state.layout.str() +
                     ", model has " + expected.str());
  }
  if (!state.IsConsistent()) throw StateError("state arrays do not match their layout");
  d->time = state.time;
  for (const auto& e : Arrays(state)) {
    if (e.length) mj_setState(m, d, e.vec->data(), e.component);
  }
}

void RestoreState(const mjModel* m, mjData* d, const PhysicsState& state) {
  ApplyState(m, d, state);
  mj_forward(m, d);
  // mj_forward normalises the quaternions in qpos in place; the next mj_step does that itself,
  // and normalising twice is not the identity in the last bit.
  if (!state.qpos.empty()) mj_setState(m, d, state.qpos.data(), mjSTATE_QPOS);
  if (!state.qacc_warmstart.empty()) {
    mj_setState(m, d, state.qacc_warmstart.data(), mjSTATE_WARMSTART);
  }
}

std::vector<std::uint8_t> SerializeState(const PhysicsState& state) {
  if (!state.IsConsistent()) throw StateError("cannot serialise: state arrays do not match layout");
  std::uint64_t payload = 0;
  for (const auto& e : Arrays(state)) payload += e.vec->size() * sizeof(mjtNum);
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderSize + payload + kChecksumSize);
  Put(&out, kMagic, 4);
  const std::uint32_t version = kStateFormatVersion;
  const std::uint32_t header = kHeaderSize;
  Put(&out, &version, 4);
  Put(&out, &header, 4);
  const StateLayout& l = state.layout;
  for (std::int32_t v : {l.nq, l.nv, l.na, l.nu, l.nbody, l.nmocap, l.nuserdata, l.nhistory, l.neq,
                         l.npluginstate}) {
    Put(&out, &v, 4);
  }
  Put(&out, &state.time, 8);
  Put(&out, &payload, 8);
  for (const auto& e : Arrays(state)) {
    if (!e.vec->empty()) Put(&out, e.vec->data(), e.vec->size() * sizeof(mjtNum));
  }
  const std::uint64_t sum = Fnv1a(out.data(), out.size());
  Put(&out, &sum, 8);
  return out;
}

PhysicsState DeserializeState(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < 4 || std::memcmp(bytes.data(), kMagic, 4) != 0) {
    throw StateError("not URLab state data (bad magic number)");
  }
  Reader r(bytes);
  r.Get<std::uint32_t>("magic");
  const auto version = r.Get<std::uint32_t>("version");
  if (version != kStateFormatVersion) {
    throw StateError("unsupported state format version " + std::to_string(version) +
                     " (this build reads version " + std::to_string(kStateFormatVersion) + ")");
  }
  const auto header = r.Get<std::uint32_t>("header size");
  if (header != kHeaderSize) {
    throw StateError("corrupt state header: header size " + std::to_string(header) + ", expected " +
                     std::to_string(kHeaderSize));
  }
  PhysicsState s;
  StateLayout& l = s.layout;
  for (int* f : {&l.nq, &l.nv, &l.na, &l.nu, &l.nbody, &l.nmocap, &l.nuserdata, &l.nhistory, &l.neq,
                 &l.npluginstate}) {
    *f = r.Get<std::int32_t>("layout");
  }
  s.time = r.Get<double>("time");
  const auto payload = r.Get<std::uint64_t>("payload size");
  std::uint64_t expected = 0;
  for (const auto& e : Arrays(s)) {
    if (e.length < 0 || e.length > kMaxArrayLength) {
      throw StateError(std::string("corrupt state header: bad length for ") + e.name + " (" +
                       l.str() + ")");
    }
    expected += static_cast<std::uint64_t>(e.length) * sizeof(mjtNum);
  }
  if (payload != expected) {
    throw StateError("corrupt state header: payload of " + std::to_string(payload) +
                     " bytes but the layout (" + l.str() + ") needs " + std::to_string(expected));
  }
  const std::uint64_t total = kHeaderSize + payload + kChecksumSize;
  if (bytes.size() != total) {
    throw StateError("state data has " + std::to_string(bytes.size()) + " bytes, expected " +
                     std::to_string(total) + (bytes.size() < total ? " (truncated)" : ""));
  }
  for (auto& e : Arrays(s)) r.GetArray(e.vec, e.length, e.name);
  const std::size_t summed = r.pos();
  const auto sum = r.Get<std::uint64_t>("checksum");
  if (sum != Fnv1a(bytes.data(), summed))
    throw StateError("state data checksum mismatch (corrupt)");
  return s;
}

}  // namespace urlab::physics
