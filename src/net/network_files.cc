#include "net/network_files.h"

#include <sys/stat.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <system_error>

#include "net/request_fields.h"

namespace urlab::net {

namespace fs = std::filesystem;
using request::Fail;

namespace {

// What is at `path` without following a final link: none, a regular file, or something else
// (a link, a FIFO, a device, a folder).
enum class Kind { kNone, kRegular, kOther };

Kind KindAt(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return errno == ENOENT ? Kind::kNone : Kind::kOther;
  return S_ISREG(st.st_mode) ? Kind::kRegular : Kind::kOther;
}

const char* Describe(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return "unreadable";
  if (S_ISLNK(st.st_mode)) return "a symbolic link";
  if (S_ISFIFO(st.st_mode)) return "a FIFO";
  if (S_ISDIR(st.st_mode)) return "a folder";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "a device";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

NetworkFiles::NetworkFiles(const std::string& dir, std::vector<std::string> inputs)
    : inputs_(std::move(inputs)) {
  std::error_code ec;
  fs::path p = fs::absolute(dir.empty() ? std::string(kDefaultFilesDir) : dir, ec);
  dir_ = (ec ? fs::path(dir) : p).lexically_normal().string();
  while (dir_.size() > 1 && dir_.back() == '/') dir_.pop_back();
}

std::string NetworkFiles::NameOf(const std::string& given, const char* field) const {
  fs::path p(given);
  if (given.empty() || !p.is_absolute()) return given;
  p = p.lexically_normal();
  const std::string leaf = p.filename().string();
  const fs::path folder = p.parent_path();
  std::error_code ec;
  // The same folder by another spelling (a link to it, a bind mount) writes and reads in it
  // too: the file is always opened as dir_/leaf, never through `given`.
  if (!leaf.empty() && (folder == fs::path(dir_) || fs::equivalent(folder, dir_, ec))) {
    return leaf;
  }
  Fail("bad_file_name", std::string("'") + field + "': " + given +
                            " is not a file in the server's files folder " + dir_ +
                            " (network.files_dir); give a file name, or a path directly in it");
}

std::string NetworkFiles::PathOf(const std::string& name, const char* field) const {
  const auto refuse = [&](const std::string& why) {
    Fail("bad_file_name", std::string("'") + field +
                              "' must be a file name in the server's files " +
                              "folder (network.files_dir), not a path: " + why);
  };
  if (name.empty()) refuse("it is empty");
  if (name.size() > kMaxFileNameBytes) {
    refuse("longer than " + std::to_string(kMaxFileNameBytes) + " bytes");
  }
  if (name.find('/') != std::string::npos || name.find('\\') != std::string::npos) {
    refuse("'" + name + "' has a folder separator");
  }
  if (name.front() == '.') refuse("'" + name + "' starts with '.' ('..', hidden or temporary)");
  for (const char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) refuse("it has a control character");
  }
  return dir_ + "/" + name;
}

std::string NetworkFiles::ForReading(const std::string& name, const char* field) const {
  const std::string path = PathOf(name, field);
  switch (KindAt(path)) {
    case Kind::kRegular:
      return path;
    case Kind::kNone:
      Fail("path_not_readable", "no file '" + name + "' in " + dir_);
    case Kind::kOther:
      break;
  }
  Fail("path_not_readable", "'" + name + "' in " + dir_ + " is " + Describe(path) +
                                ", not a regular file; nothing was read");
}

std::string NetworkFiles::ForWriting(const std::string& name, const char* field, bool overwrite,
                                     const std::vector<std::string>& also) const {
  const std::string path = PathOf(name, field);
  if (name.size() >= std::strlen(kPartSuffix) &&
      name.compare(name.size() - std::strlen(kPartSuffix), std::string::npos, kPartSuffix) == 0) {
    Fail("bad_file_name", std::string("'") + field +
                              "': names ending in .part are the recorder's " +
                              "partial files; they are read, never written");
  }
  std::error_code ec;
  for (const std::string& input : inputs_) {
    if (fs::equivalent(path, input, ec)) {
      Fail("file_is_input", "'" + name + "' is " + input +
                                ", an input of the running simulation; it is never written");
    }
  }
  std::vector<std::string> targets{path};
  for (const std::string& suffix : also) targets.push_back(path + suffix);
  for (const std::string& t : targets) {
    const Kind k = KindAt(t);
    if (k == Kind::kOther) {
      Fail("path_not_writable", t + " is " + Describe(t) + "; only regular files are written");
    }
    if (k == Kind::kRegular && t == path && !overwrite) {
      Fail("file_exists", "'" + name + "' exists in " + dir_ +
                              "; send overwrite: true (with the driver lease) to replace it");
    }
  }
  fs::create_directories(dir_, ec);
  if (!fs::is_directory(dir_, ec)) {
    Fail("path_not_writable", "the files folder " + dir_ + " is not a folder" +
                                  (ec ? " (" + ec.message() + ")" : std::string()));
  }
  return path;
}

std::string NetworkFiles::FreshName(const std::string& stem, const std::string& ext) const {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &utc);
  const std::string base = stem + "-" + stamp;
  for (int n = 1;; ++n) {
    const std::string name = base + (n == 1 ? std::string() : "-" + std::to_string(n)) + ext;
    const std::string path = dir_ + "/" + name;
    if (KindAt(path) == Kind::kNone && KindAt(path + kPartSuffix) == Kind::kNone) return name;
  }
}

}  // namespace urlab::net
