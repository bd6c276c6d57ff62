#pragma once
// Reading MJCF files into documents. Resolves <include> (relative to the main file's folder, as
// MuJoCo 2.2.2 does), checks every element and attribute value against the grammar, checks that
// asset files exist and that every attribute naming another element names one that exists.
// Errors are urlab::InputError naming the file and line; the first of a kind is thrown with
// "(and N more)". A path that is not a regular file (FIFO, device, folder) or is larger than
// kMaxTextInputBytes is refused before reading. Thread: any; no shared state.
#include <string>
#include <vector>

#include "urlab/core/diagnostics.h"
#include "urlab/core/error.h"
#include "urlab/document/document.h"

namespace urlab::mjcf {

struct ReadOptions {
  bool check_files = true;       // asset files must exist
  bool check_references = true;  // names used by attributes must be defined
};

// Reads the model at `path`. Throws InputError.
document::Document ReadFile(const std::string& path, const ReadOptions& options = {});

// Reads a model held in memory; `virtual_path` names it in messages and its folder is where
// relative includes and assets resolve. Throws InputError.
document::Document ReadString(const std::string& xml, const std::string& virtual_path,
                              const ReadOptions& options = {});

// The checks the reader runs (and `urlab validate` runs on a leniently read document), each
// adding every problem it finds to `sink` as an error at the element's file:line, with `label`
// prefixed to the message (e.g. the articulation: "left: ").
// Every attribute that names an element which does not exist.
void FindDanglingReferences(const document::Document& doc, Diagnostics& sink,
                            const std::string& label = {});
// Every second definition of a name within one namespace.
void FindDuplicateNames(const document::Document& doc, Diagnostics& sink,
                        const std::string& label = {});
// Every file attribute whose file does not exist.
void FindMissingFiles(const document::Document& doc, Diagnostics& sink,
                      const std::string& label = {});

// Every file a document was read from or names: the main file, its includes, and the resolved
// asset files (absolute paths, sorted, each once). Outputs must never overwrite one of them.
std::vector<std::string> InputFiles(const document::Document& doc);

}  // namespace urlab::mjcf
