#pragma once
// Reading MJCF files into documents. Resolves <include> (relative to the main file's folder, as
// MuJoCo 2.2.2 does), checks every element and attribute value against the grammar, checks that
// asset files exist and that every attribute naming another element names one that exists.
// Errors are urlab::InputError naming the file and line. Thread: any; no shared state.
#include <string>
#include <vector>

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

// Every attribute that names an element which does not exist, as errors with locations.
std::vector<InputError> FindDanglingReferences(const document::Document& doc);

// Every second definition of a name within one namespace, as errors with locations.
std::vector<InputError> FindDuplicateNames(const document::Document& doc);

// Every file attribute whose file does not exist, as errors with locations.
std::vector<InputError> FindMissingFiles(const document::Document& doc);

}  // namespace urlab::mjcf
