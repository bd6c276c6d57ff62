// corpus_check: load MJCF files with the system MuJoCo (2.2.2) and simulate them.
//
// Build:  g++ -O2 -std=c++17 tools/corpus_check/check.cc -o /tmp/corpus_check -lmujoco
// Usage:  corpus_check [--steps N] [--expect-reject] [--schema] FILE...
//
// For every FILE one tab-separated line is printed:
//   <status> <file> <details>
// status is one of
//   OK         loaded without error or warning, simulated without warning
//   REJECT     mj_loadXML returned NULL (details: MuJoCo's error message)
//   LOADWARN   model loaded but the compiler reported a warning in the error buffer
//   SIMWARN    a warning or error was raised while simulating (details say which)
//   STATIC     loaded and simulated cleanly but nothing moved (no dof changed)
// Simulation passes: (1) zero control from qpos0, (2) sinusoidal control inside
// ctrlrange, (3) every keyframe as initial state, each for N steps (default 1000).
// Pass 1 is run twice and must be bit-identical (determinism check).
// Exit code: 0 when every file is OK (or, with --expect-reject, every file is REJECT).
#include <mujoco/mujoco.h>

#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

static std::string g_msgs;
static jmp_buf g_jmp;
static bool g_jmp_armed = false;

static void on_warning(const char* msg) {
  if (!g_msgs.empty()) g_msgs += " | ";
  g_msgs += "warning: ";
  g_msgs += msg;
}

static void on_error(const char* msg) {
  if (!g_msgs.empty()) g_msgs += " | ";
  g_msgs += "error: ";
  g_msgs += msg;
  if (g_jmp_armed) longjmp(g_jmp, 1);
  fprintf(stderr, "fatal MuJoCo error outside simulation: %s\n", msg);
  exit(3);
}

static std::string oneline(const char* s) {
  std::string r;
  for (const char* p = s; *p; ++p) r += (*p == '\n' || *p == '\t') ? ' ' : *p;
  while (!r.empty() && r.back() == ' ') r.pop_back();
  return r;
}

static void set_ctrl(const mjModel* m, mjData* d, bool sinus) {
  for (int i = 0; i < m->nu; ++i) {
    if (!sinus) {
      d->ctrl[i] = 0;
      continue;
    }
    double s = 0.5 + 0.5 * std::sin(2 * M_PI * (0.7 + 0.13 * i) * d->time);
    if (m->actuator_ctrllimited[i]) {
      double lo = m->actuator_ctrlrange[2 * i], hi = m->actuator_ctrlrange[2 * i + 1];
      d->ctrl[i] = lo + (hi - lo) * s;
    } else {
      d->ctrl[i] = 2 * s - 1;
    }
  }
}

struct RunResult {
  bool ok = true;
  std::string why;
  double maxdisp = 0;
  std::vector<double> state;
};

static RunResult run(const mjModel* m, int steps, bool sinus, int key) {
  RunResult r;
  mjData* d = mj_makeData(m);
  if (key >= 0) mj_resetDataKeyframe(m, d, key);
  std::vector<double> q0(d->qpos, d->qpos + m->nq);
  std::vector<double> mp0(d->mocap_pos, d->mocap_pos + 3 * m->nmocap);
  g_msgs.clear();
  g_jmp_armed = true;
  if (setjmp(g_jmp) == 0) {
    for (int t = 0; t < steps; ++t) {
      set_ctrl(m, d, sinus);
      mj_step(m, d);
      for (int i = 0; i < m->nq; ++i) {
        double dq = std::fabs(d->qpos[i] - q0[i]);
        if (!std::isfinite(d->qpos[i])) {
          r.ok = false;
          r.why = "non-finite qpos";
          break;
        }
        if (dq > r.maxdisp) r.maxdisp = dq;
      }
      if (!r.ok) break;
    }
  } else {
    r.ok = false;
  }
  g_jmp_armed = false;
  for (int w = 0; w < mjNWARNING; ++w) {
    if (d->warning[w].number) {
      r.ok = false;
      char buf[128];
      snprintf(buf, sizeof buf, "mjWARN %d x%d (info %d)", w, d->warning[w].number,
               d->warning[w].lastinfo);
      if (!r.why.empty()) r.why += "; ";
      r.why += buf;
    }
  }
  if (!g_msgs.empty()) {
    r.ok = false;
    if (!r.why.empty()) r.why += "; ";
    r.why += oneline(g_msgs.c_str());
  }
  r.state.assign(d->qpos, d->qpos + m->nq);
  r.state.insert(r.state.end(), d->qvel, d->qvel + m->nv);
  r.state.insert(r.state.end(), d->act, d->act + m->na);
  mj_deleteData(d);
  return r;
}

int main(int argc, char** argv) {
  int steps = 1000;
  bool expect_reject = false;
  std::vector<const char*> files;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--steps") && i + 1 < argc)
      steps = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--expect-reject"))
      expect_reject = true;
    else if (!strcmp(argv[i], "--schema")) {
      std::vector<char> buf(1 << 20);
      mj_printSchema(nullptr, buf.data(), (int)buf.size(), 0, 0);
      fputs(buf.data(), stdout);
      return 0;
    } else
      files.push_back(argv[i]);
  }
  mju_user_warning = on_warning;
  mju_user_error = on_error;
  int bad = 0;
  for (const char* f : files) {
    char err[2000] = "";
    g_msgs.clear();
    mjModel* m = mj_loadXML(f, nullptr, err, sizeof err);
    std::string loadmsgs = g_msgs;
    if (!m) {
      printf("REJECT\t%s\t%s\n", f, oneline(err).c_str());
      if (!expect_reject) ++bad;
      continue;
    }
    if (expect_reject) ++bad;
    if (err[0] || !loadmsgs.empty()) {
      printf("LOADWARN\t%s\t%s %s\n", f, oneline(err).c_str(), oneline(loadmsgs.c_str()).c_str());
      mj_deleteModel(m);
      ++bad;
      continue;
    }
    std::string why;
    double maxdisp = 0;
    RunResult a = run(m, steps, false, -1);
    if (!a.ok) why += "zero-ctrl: " + a.why + "; ";
    maxdisp = a.maxdisp;
    RunResult a2 = run(m, steps, false, -1);
    if (a.ok && a2.state != a.state) why += "non-deterministic; ";
    if (m->nu) {
      RunResult b = run(m, steps, true, -1);
      if (!b.ok) why += "sin-ctrl: " + b.why + "; ";
      if (b.maxdisp > maxdisp) maxdisp = b.maxdisp;
    }
    for (int k = 0; k < m->nkey; ++k) {
      RunResult c = run(m, steps, false, k);
      if (!c.ok) why += "key" + std::to_string(k) + ": " + c.why + "; ";
    }
    char info[256];
    snprintf(info, sizeof info,
             "nq=%d nv=%d nu=%d na=%d nbody=%d ngeom=%d nsite=%d ntendon=%d neq=%d nsensor=%d "
             "nmesh=%d ntex=%d nkey=%d maxdisp=%.3g",
             m->nq, m->nv, m->nu, m->na, m->nbody, m->ngeom, m->nsite, m->ntendon, m->neq,
             m->nsensor, m->nmesh, m->ntex, m->nkey, maxdisp);
    if (!why.empty()) {
      printf("SIMWARN\t%s\t%s %s\n", f, why.c_str(), info);
      ++bad;
    } else if (maxdisp < 1e-6) {
      printf("STATIC\t%s\t%s\n", f, info);
      ++bad;
    } else {
      printf("OK\t%s\t%s\n", f, info);
    }
    mj_deleteModel(m);
  }
  return bad ? 1 : 0;
}
