#pragma once
// The files the step server reads and writes for its clients (snapshots, recordings, replays).
// A client names a file, never a path: one name (no '/', no "..", no leading '.', no control
// characters, at most kMaxFileNameBytes) under one folder the scene or the command line chooses
// (network.files_dir, `--files-dir`; by default `recordings/` in the run's working folder).
// Writes never replace an input of the running process (scene file, MJCF files, meshes), never
// go through a symbolic link or into a FIFO or device, and never replace an existing file unless
// the request says `overwrite` (the caller makes that hold the driver lease). Reads open only
// regular files under the folder.
//
// Every refusal is a request::Failure with the protocol's code: bad_file_name, file_exists,
// file_is_input, path_not_writable, path_not_readable.
//
// Thread: the network I/O thread (built on the main thread); no shared state.
#include <cstddef>
#include <string>
#include <vector>

namespace urlab::net {

// The default folder, relative to the working folder of the run.
inline constexpr const char* kDefaultFilesDir = "recordings";
// A longer name is refused (room is left for the ".part" and temporary suffixes the writers add).
inline constexpr std::size_t kMaxFileNameBytes = 200;
// Names ending in this are the recorder's partial files: readable (replay_load), never written.
inline constexpr const char* kPartSuffix = ".part";

class NetworkFiles {
 public:
  // `dir` is made absolute against the current working folder now; `inputs` are the files the
  // running process read (compared by identity, so other spellings and links are caught).
  NetworkFiles(const std::string& dir, std::vector<std::string> inputs);

  const std::string& dir() const { return dir_; }

  // The file name a path a client gave names (request field `field`), for the clients that send
  // the absolute paths their users type (the 2026 dialect's recording_save and replay_load): an
  // absolute path whose folder is this folder (after removing "." and "..", or the same folder
  // reached another way) is its last component, judged then as any name; an absolute path
  // elsewhere is refused (bad_file_name, naming the folder); anything else is returned as it is.
  std::string NameOf(const std::string& given, const char* field) const;
  // The path of the file a client called `name` (request field `field`); throws bad_file_name.
  std::string PathOf(const std::string& name, const char* field) const;
  // A file to read: an existing regular file (not a link) under the folder.
  std::string ForReading(const std::string& name, const char* field) const;
  // A file to write, the folder created when missing. Refused: a name ending in ".part", an
  // input of the process (file_is_input), an existing file without `overwrite` (file_exists),
  // anything that is not a regular file, at the name or at any of `also` (suffixes the writer
  // uses next to it, e.g. ".part"): path_not_writable.
  std::string ForWriting(const std::string& name, const char* field, bool overwrite,
                         const std::vector<std::string>& also = {}) const;
  // A name that is free in the folder: "{stem}-{UTC yyyymmdd-hhmmss}{-n}{ext}".
  std::string FreshName(const std::string& stem, const std::string& ext) const;

 private:
  std::string dir_;
  std::vector<std::string> inputs_;
};

}  // namespace urlab::net
