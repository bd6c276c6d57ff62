#include "urlab/replay/csv.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>

#include "urlab/core/error.h"
#include "urlab/core/files.h"

namespace urlab::replay {

namespace {

// Sensor columns start with this; import skips them.
constexpr std::string_view kSensorColumn = "sensor:";

// Below this norm a quaternion is zero (MuJoCo's mjMINVAL).
constexpr double kMinQuatNorm = 1e-15;
// A quaternion whose norm is off 1 by at most this is kept as it is (bit for bit).
constexpr double kQuatNormTolerance = 1e-12;

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsBlank(s.back())) s.remove_suffix(1);
  return s;
}

bool IsBlankLine(std::string_view s) { return Trim(s).empty(); }

// The whole file, read straight into one string (ReadInputFile's stream copies would double the
// time of a large import).
std::string ReadCsvFile(const std::string& path) {
  CheckInputFile(path, "CSV file", {}, kMaxCsvBytes);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError({path, 0}, std::string("cannot open CSV file: ") + std::strerror(errno));
  std::string text;
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  text.resize(ec ? 0 : static_cast<std::size_t>(size));
  std::size_t got = std::fread(text.data(), 1, text.size(), f);
  // A file that grew since: read the rest, up to the limit.
  char buf[1 << 16];
  while (got == text.size()) {
    const std::size_t n = std::fread(buf, 1, sizeof buf, f);
    if (n == 0) break;
    text.append(buf, n);
    got += n;
    if (got > kMaxCsvBytes) {
      std::fclose(f);
      throw InputError({path, 0}, "CSV file grew past the size URLab reads while being read");
    }
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw InputError({path, 0}, "cannot read CSV file");
  text.resize(got);
  return text;
}

// The header's cells: trimmed, double quotes removed ("" inside quotes is a quote).
std::vector<std::string> SplitHeader(std::string_view line, const std::string& path) {
  std::vector<std::string> cells;
  std::size_t i = 0;
  const auto fail = [&](const std::string& why) {
    throw InputError({path, 1}, fmt::format("header, column {}: {}", cells.size() + 1, why));
  };
  while (true) {
    while (i < line.size() && IsBlank(line[i])) ++i;
    std::string cell;
    if (i < line.size() && line[i] == '"') {
      ++i;
      while (true) {
        if (i >= line.size()) fail("no closing double quote");
        if (line[i] == '"') {
          if (i + 1 < line.size() && line[i + 1] == '"') {
            cell += '"';
            i += 2;
            continue;
          }
          ++i;
          break;
        }
        cell += line[i++];
      }
      while (i < line.size() && IsBlank(line[i])) ++i;
      if (i < line.size() && line[i] != ',') fail("text after the closing double quote");
    } else {
      const std::size_t comma = std::min(line.find(',', i), line.size());
      cell = std::string(Trim(line.substr(i, comma - i)));
      i = comma;
    }
    cells.push_back(std::move(cell));
    if (i >= line.size()) break;
    ++i;  // the comma
  }
  return cells;
}

// Joints named `name` as a short name (when no joint has it as its full name).
int ShortNameCount(const ModelTables& tables, std::string_view name) {
  int n = 0;
  for (const JointEntry& j : tables.joints) {
    if (j.name == name) return 0;
    if (j.short_name == name) ++n;
  }
  return n;
}

// What a header cell names.
struct ColumnMatch {
  enum Kind { kNone, kQpos, kQvel, kAmbiguous, kOutOfRange } kind = kNone;
  const JointEntry* joint = nullptr;
  int index = 0;         // value of the joint: 0 .. nq-1 (kQpos) or nv-1 (kQvel)
  bool indexed = false;  // named with [i]
  std::string base;      // the joint's name as the column spells it (without [i] and .v)
};

// "name[12]" -> ("name", 12); false when `cell` has no well-formed index suffix.
bool SplitIndex(std::string_view cell, std::string_view* base, int* index) {
  if (cell.size() < 3 || cell.back() != ']') return false;
  const std::size_t open = cell.rfind('[');
  if (open == std::string_view::npos || open == 0 || open + 2 > cell.size() - 1) return false;
  const char* first = cell.data() + open + 1;
  const char* last = cell.data() + cell.size() - 1;
  const auto [ptr, ec] = std::from_chars(first, last, *index);
  if (ec != std::errc() || ptr != last || *index < 0) return false;
  *base = cell.substr(0, open);
  return true;
}

ColumnMatch MatchColumn(const ModelTables& tables, std::string_view cell) {
  ColumnMatch m;
  std::string_view base = cell;
  int index = 0;
  bool indexed = false;
  // The whole cell first: a joint's name may itself end in "]" or ".v".
  const JointEntry* j = tables.FindJoint(cell);
  if (!j) indexed = SplitIndex(cell, &base, &index);
  if (indexed) j = tables.FindJoint(base);
  bool velocity = false;
  std::vector<std::string_view> tried = {cell, base};
  if (!j && base.ends_with(".v")) {
    base.remove_suffix(2);
    tried.push_back(base);
    j = tables.FindJoint(base);
    velocity = j != nullptr;
  }
  if (!j) {
    for (std::string_view name : tried) {
      if (ShortNameCount(tables, name) > 1) m.kind = ColumnMatch::kAmbiguous;
    }
    return m;
  }
  m.joint = j;
  m.index = index;
  m.indexed = indexed;
  m.base = std::string(base);
  const int size = velocity ? j->nv : j->nq;
  if (index >= size) {
    m.kind = ColumnMatch::kOutOfRange;
  } else {
    m.kind = velocity ? ColumnMatch::kQvel : ColumnMatch::kQpos;
  }
  return m;
}

// Where a cell's value goes.
struct Target {
  enum Kind : unsigned char { kSkip, kTime, kQpos, kQvel } kind = kSkip;
  int index = 0;  // in the qpos or qvel row
};

// A quaternion to normalise in every row.
struct Quaternion {
  int qpos_index = 0;  // of w
  std::string label;   // the joint and its four columns, for messages
};

class Parser {
 public:
  Parser(const std::string& path, const ModelTables& tables, const std::vector<double>& qpos0,
         CsvImportReport* report)
      : path_(path), tables_(tables), qpos0_(qpos0), report_(report) {}

  Trajectory Run() {
    const std::string text = ReadCsvFile(path_);
    std::string_view rest = text;
    if (rest.starts_with("\xEF\xBB\xBF")) rest.remove_prefix(3);  // UTF-8 byte order mark
    if (std::all_of(rest.begin(), rest.end(),
                    [](char c) { return IsBlank(c) || c == '\r' || c == '\n'; })) {
      throw InputError({path_, 1}, "empty CSV file: no header and no data");
    }
    const std::string_view header = NextLine(&rest);
    if (IsBlankLine(header)) {
      throw InputError({path_, 1}, "the first line is blank; it must be the header");
    }
    MapColumns(SplitHeader(header, path_));

    Trajectory traj;
    traj.nq = tables_.nq;
    traj.nv = tables_.nv;
    const std::size_t expected_rows =
        static_cast<std::size_t>(std::count(rest.begin(), rest.end(), '\n')) + 1;
    traj.time.reserve(expected_rows);
    traj.qpos.reserve(expected_rows * qpos0_.size());
    if (any_velocity_) traj.qvel.reserve(expected_rows * static_cast<std::size_t>(tables_.nv));

    int line_number = 1;
    int first_blank = 0;
    while (!rest.empty()) {
      const std::string_view line = NextLine(&rest);
      ++line_number;
      if (IsBlankLine(line)) {
        if (first_blank == 0) first_blank = line_number;
        continue;
      }
      if (first_blank != 0) {
        throw InputError(
            {path_, first_blank},
            fmt::format("blank line inside the data (line {} has a row)", line_number));
      }
      ParseRow(line, line_number, &traj);
    }
    if (traj.rows() == 0) throw InputError({path_, 1}, "a header but no data rows");
    return traj;
  }

 private:
  // The next line (without its "\n" or "\r\n"), removed from *rest.
  static std::string_view NextLine(std::string_view* rest) {
    const std::size_t nl = rest->find('\n');
    std::string_view line = rest->substr(0, nl);
    rest->remove_prefix(nl == std::string_view::npos ? rest->size() : nl + 1);
    if (line.ends_with('\r')) line.remove_suffix(1);
    return line;
  }

  std::string Column(int c) const {
    return fmt::format("column {} '{}'", c + 1, header_[static_cast<std::size_t>(c)]);
  }

  [[noreturn]] void HeaderError(const std::string& why) const { throw InputError({path_, 1}, why); }

  void MapColumns(std::vector<std::string> header) {
    header_ = std::move(header);
    const int ncols = static_cast<int>(header_.size());
    targets_.assign(header_.size(), {});
    // The column giving each qpos/qvel value (-1: none) and the spelling of each joint.
    std::vector<int> qpos_column(static_cast<std::size_t>(tables_.nq), -1);
    std::vector<int> qvel_column(static_cast<std::size_t>(tables_.nv), -1);
    std::vector<std::string> spelled(tables_.joints.size());
    int time_column = -1;
    CsvImportReport report;
    for (int c = 0; c < ncols; ++c) {
      const std::string& name = header_[static_cast<std::size_t>(c)];
      Target& target = targets_[static_cast<std::size_t>(c)];
      if (name == "time") {
        if (time_column >= 0) {
          HeaderError(fmt::format("two time columns: {} and {}", time_column + 1, c + 1));
        }
        time_column = c;
        target.kind = Target::kTime;
        continue;
      }
      if (name.starts_with(kSensorColumn)) continue;  // recorded sensor values: not state
      const ColumnMatch m = MatchColumn(tables_, name);
      switch (m.kind) {
        case ColumnMatch::kNone:
        case ColumnMatch::kOutOfRange:
          report.unmatched_columns.push_back(name.empty() ? fmt::format("(column {})", c + 1)
                                                          : name);
          continue;
        case ColumnMatch::kAmbiguous:
          report.ambiguous_columns.push_back(name);
          continue;
        case ColumnMatch::kQpos:
        case ColumnMatch::kQvel:
          break;
      }
      const JointEntry& j = *m.joint;
      const bool velocity = m.kind == ColumnMatch::kQvel;
      const int size = velocity ? j.nv : j.nq;
      if (size > 1 && !m.indexed) {
        const std::string stem = velocity ? m.base + ".v" : m.base;
        HeaderError(fmt::format(
            "{}: {} is a {} joint with {} {} values; name its columns {}[0] .. {}[{}]", Column(c),
            j.name, JointTypeName(j.type), size, velocity ? "qvel" : "qpos", stem, stem, size - 1));
      }
      std::vector<int>& columns = velocity ? qvel_column : qpos_column;
      const int slot = (velocity ? j.dofadr : j.qposadr) + m.index;
      int& owner = columns[static_cast<std::size_t>(slot)];
      if (owner >= 0) {
        HeaderError(fmt::format("{} and {} both give {} of joint {}", Column(owner), Column(c),
                                size > 1 ? fmt::format("value {}", m.index) : "the value", j.name));
      }
      owner = c;
      target.kind = velocity ? Target::kQvel : Target::kQpos;
      target.index = slot;
      if (velocity) any_velocity_ = true;
      std::string& spelling = spelled[static_cast<std::size_t>(&j - tables_.joints.data())];
      if (spelling.empty()) spelling = m.base;
    }
    if (time_column < 0) HeaderError("no 'time' column");

    // Every joint: all of its columns or none.
    for (std::size_t ji = 0; ji < tables_.joints.size(); ++ji) {
      const JointEntry& j = tables_.joints[ji];
      for (const bool velocity : {false, true}) {
        const std::vector<int>& columns = velocity ? qvel_column : qpos_column;
        const int adr = velocity ? j.dofadr : j.qposadr;
        const int size = velocity ? j.nv : j.nq;
        std::string missing;
        int present = 0;
        for (int k = 0; k < size; ++k) {
          if (columns[static_cast<std::size_t>(adr + k)] >= 0) {
            ++present;
          } else {
            missing += fmt::format("{}{}{}[{}]", missing.empty() ? "" : ", ", spelled[ji],
                                   velocity ? ".v" : "", k);
          }
        }
        if (present > 0 && present < size) {
          HeaderError(fmt::format("joint {} has {} of its {} {} columns; missing: {}", j.name,
                                  present, size, velocity ? "qvel" : "qpos", missing));
        }
        if (present == 0 && !velocity) report.unmatched_joints.push_back(j.name);
        if (present == 0 && velocity) report.joints_without_velocity.push_back(j.name);
        if (present == size && !velocity && (j.type == mjJNT_FREE || j.type == mjJNT_BALL)) {
          const int w = j.qposadr + (j.type == mjJNT_FREE ? 3 : 0);
          std::string label = "joint " + j.name + " (";
          for (int k = 0; k < 4; ++k) {
            label += (k ? ", " : "") + Column(qpos_column[static_cast<std::size_t>(w + k)]);
          }
          label += ')';
          quaternions_.push_back({w, std::move(label)});
        }
      }
    }
    if (!any_velocity_) report.joints_without_velocity.clear();
    if (report_) *report_ = std::move(report);
  }

  double ParseNumber(const char* first, const char* last, int c, int line_number) const {
    while (first < last && IsBlank(*first)) ++first;
    while (last > first && IsBlank(last[-1])) --last;
    if (last - first >= 2 && *first == '"' && last[-1] == '"') {
      ++first;
      --last;
    }
    const char* number = first;
    if (last - number >= 2 && *number == '+' && number[1] != '-') ++number;
    double v = 0;
    const auto [ptr, ec] = std::from_chars(number, last, v);
    const std::string_view cell(first, static_cast<std::size_t>(last - first));
    if (ec == std::errc::result_out_of_range) {
      throw InputError({path_, line_number},
                       fmt::format("{}: '{}' is out of the range of a double", Column(c), cell));
    }
    if (ec != std::errc() || ptr != last) {
      throw InputError({path_, line_number},
                       fmt::format("{}: '{}' is not a number", Column(c), cell));
    }
    if (!std::isfinite(v)) {
      throw InputError({path_, line_number},
                       fmt::format("{}: '{}' is not a finite number", Column(c), cell));
    }
    return v;
  }

  void ParseRow(std::string_view line, int line_number, Trajectory* traj) const {
    traj->time.push_back(0);
    const std::size_t qpos_at = traj->qpos.size();
    traj->qpos.insert(traj->qpos.end(), qpos0_.begin(), qpos0_.end());
    const std::size_t qvel_at = traj->qvel.size();
    if (any_velocity_) traj->qvel.resize(qvel_at + static_cast<std::size_t>(tables_.nv), 0.0);
    double* qpos = traj->qpos.data() + qpos_at;
    double* qvel = traj->qvel.data() + qvel_at;

    const char* p = line.data();
    const char* const end = line.data() + line.size();
    const int ncols = static_cast<int>(targets_.size());
    for (int c = 0; c < ncols; ++c) {
      const char* comma =
          static_cast<const char*>(std::memchr(p, ',', static_cast<std::size_t>(end - p)));
      if ((comma == nullptr) != (c == ncols - 1)) {
        throw InputError({path_, line_number},
                         fmt::format("the row has {} cells, the header {}",
                                     std::count(line.begin(), line.end(), ',') + 1, ncols));
      }
      const char* cell_end = comma ? comma : end;
      const Target& t = targets_[static_cast<std::size_t>(c)];
      if (t.kind != Target::kSkip) {
        const double v = ParseNumber(p, cell_end, c, line_number);
        switch (t.kind) {
          case Target::kTime:
            traj->time.back() = v;
            break;
          case Target::kQpos:
            qpos[t.index] = v;
            break;
          case Target::kQvel:
            qvel[t.index] = v;
            break;
          case Target::kSkip:
            break;
        }
      }
      p = cell_end + 1;
    }

    const std::size_t row = traj->rows() - 1;
    if (row > 0 && !(traj->time[row] > traj->time[row - 1])) {
      throw InputError({path_, line_number},
                       fmt::format("time {} is not after the previous row's {}; times must "
                                   "increase strictly",
                                   traj->time[row], traj->time[row - 1]));
    }
    for (const Quaternion& q : quaternions_) {
      double* w = qpos + q.qpos_index;
      const double norm = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + w[3] * w[3]);
      if (!(norm >= kMinQuatNorm)) {
        throw InputError({path_, line_number},
                         fmt::format("{}: the quaternion (w x y z) is zero", q.label));
      }
      if (std::abs(norm - 1) > kQuatNormTolerance) {
        for (int i = 0; i < 4; ++i) w[i] /= norm;
      }
    }
  }

  const std::string& path_;
  const ModelTables& tables_;
  const std::vector<double>& qpos0_;
  CsvImportReport* report_;
  std::vector<std::string> header_;
  std::vector<Target> targets_;
  std::vector<Quaternion> quaternions_;
  bool any_velocity_ = false;
};

bool NeedsQuotes(std::string_view name) {
  return name.empty() || name.find_first_of(",\"") != std::string_view::npos ||
         IsBlank(name.front()) || IsBlank(name.back());
}

void AppendName(std::string* out, std::string_view name) {
  if (!NeedsQuotes(name)) {
    out->append(name);
    return;
  }
  *out += '"';
  for (const char ch : name) {
    if (ch == '"') *out += '"';
    *out += ch;
  }
  *out += '"';
}

void AppendNumber(std::string* out, double v) {
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out->append(buf, ptr);
}

// A name without its articulation's "{art}_" (the longest articulation prefix), else itself.
std::string ShortOf(const ModelTables& tables, const std::string& full) {
  std::size_t best = 0;
  for (const std::string& a : tables.articulations) {
    if (full.size() > a.size() + 1 && full.starts_with(a) && full[a.size()] == '_') {
      best = std::max(best, a.size() + 1);
    }
  }
  return full.substr(best);
}

// True when no other sensor has the same short name.
bool SensorShortNameUnique(const ModelTables& tables, const NamedRange& s) {
  const std::string mine = ShortOf(tables, s.name);
  for (const NamedRange& o : tables.sensors) {
    if (&o != &s && ShortOf(tables, o.name) == mine) return false;
  }
  return mine != "time" && mine.find_first_of("\r\n") == std::string::npos;
}

}  // namespace

Trajectory ImportCsv(const std::string& path, const ModelTables& tables,
                     const std::vector<double>& qpos0, CsvImportReport* report) {
  if (qpos0.size() != static_cast<std::size_t>(tables.nq)) {
    throw Error(
        fmt::format("ImportCsv: qpos0 has {} values, the model nq={}", qpos0.size(), tables.nq));
  }
  return Parser(path, tables, qpos0, report).Run();
}

void ExportCsv(const std::string& path, const ModelTables& tables, const Trajectory& traj,
               const CsvExportOptions& options) {
  traj.Check(tables);
  std::vector<std::string> names;
  for (const JointEntry& j : tables.joints) {
    if (j.name.empty()) {
      throw Error(fmt::format("{}: joint {} has no name, so it cannot have CSV columns", path,
                              &j - tables.joints.data()));
    }
    if (j.name == "time" || j.name.find_first_of("\r\n") != std::string::npos) {
      throw Error(fmt::format("{}: joint '{}' cannot be a CSV column name", path, j.name));
    }
    const bool use_short = options.short_names && j.short_name != "time" &&
                           j.short_name.find_first_of("\r\n") == std::string::npos &&
                           tables.FindJoint(j.short_name) == &j;
    names.push_back(use_short ? j.short_name : j.name);
  }
  const bool velocities = options.velocities && traj.has_qvel();
  const std::vector<double>* sensors = options.sensordata;
  if (sensors && sensors->size() != traj.rows() * static_cast<std::size_t>(tables.nsensordata)) {
    throw Error(fmt::format("{}: {} sensor values for {} rows of {}", path, sensors->size(),
                            traj.rows(), tables.nsensordata));
  }

  std::string out;
  const std::size_t values_per_row =
      1 + static_cast<std::size_t>(traj.nq) + (velocities ? static_cast<std::size_t>(traj.nv) : 0);
  out.reserve((traj.rows() + 1) * values_per_row * 24);
  out += "time";
  for (std::size_t ji = 0; ji < tables.joints.size(); ++ji) {
    const JointEntry& j = tables.joints[ji];
    for (int k = 0; k < j.nq; ++k) {
      out += ',';
      AppendName(&out, j.nq == 1 ? names[ji] : fmt::format("{}[{}]", names[ji], k));
    }
  }
  if (velocities) {
    for (std::size_t ji = 0; ji < tables.joints.size(); ++ji) {
      const JointEntry& j = tables.joints[ji];
      for (int k = 0; k < j.nv; ++k) {
        out += ',';
        AppendName(&out, j.nv == 1 ? names[ji] + ".v" : fmt::format("{}.v[{}]", names[ji], k));
      }
    }
  }
  if (sensors) {
    for (const NamedRange& s : tables.sensors) {
      const bool use_short = options.short_names && SensorShortNameUnique(tables, s);
      const std::string name =
          std::string(kSensorColumn) + (use_short ? ShortOf(tables, s.name) : s.name);
      for (int k = 0; k < s.dim; ++k) {
        out += ',';
        AppendName(&out, s.dim == 1 ? name : fmt::format("{}[{}]", name, k));
      }
    }
  }
  out += '\n';
  for (std::size_t r = 0; r < traj.rows(); ++r) {
    AppendNumber(&out, traj.time[r]);
    const double* qpos = traj.qpos_row(r);
    for (const JointEntry& j : tables.joints) {
      for (int k = 0; k < j.nq; ++k) {
        out += ',';
        AppendNumber(&out, qpos[j.qposadr + k]);
      }
    }
    if (velocities) {
      const double* qvel = traj.qvel_row(r);
      for (const JointEntry& j : tables.joints) {
        for (int k = 0; k < j.nv; ++k) {
          out += ',';
          AppendNumber(&out, qvel[j.dofadr + k]);
        }
      }
    }
    if (sensors) {
      const double* row = sensors->data() + r * static_cast<std::size_t>(tables.nsensordata);
      for (const NamedRange& s : tables.sensors) {
        for (int k = 0; k < s.dim; ++k) {
          out += ',';
          AppendNumber(&out, row[s.adr + k]);
        }
      }
    }
    out += '\n';
  }
  WriteFileAtomic(path, out);
}

}  // namespace urlab::replay
