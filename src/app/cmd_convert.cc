// `urlab convert MESH -o OUT.xml`: a mesh of any readable format becomes a stand-alone MJCF
// model (the editor's Decompose Mesh button): the visual mesh in group 2, the convex parts of
// our decomposition (written as STL files in OUT_parts/) in group 3. The model is compiled as a
// check before OUT.xml and OUT_parts/ are written, so a model MuJoCo refuses leaves nothing.
// Ctrl-C, SIGTERM or SIGHUP reach the decomposition's worker threads: it stops within a unit of
// work, nothing is written and the exit code is 128+signal.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "app/commands.h"
#include "app/signals.h"
#include "app/validators.h"
#include "urlab/convert/prop.h"
#include "urlab/core/files.h"
#include "urlab/document/element.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab::app {

namespace {

struct ConvertArgs {
  std::string mesh, out, mode = "static", cache_dir;
  double threshold = 0.05;
  int max_parts = 32;
  int resolution = 50;
  int threads = 0;
  bool no_cache = false;
  std::optional<double> mass, density;
};

// The prop model compiled as a check; a MuJoCo message is located at the mesh file, naming the
// generated element (the generated text's line numbers mean nothing to the user).
void CheckCompiles(const convert::PropDocument& prop, const std::string& mesh) {
  mjcf::LineMap map;
  const std::string xml = mjcf::WriteString(prop.doc, {}, &map);  // absolute paths
  try {
    physics::CompileXmlString(xml);
  } catch (const physics::CompileError& e) {
    std::string message = e.what();
    std::string element;
    if (const auto line = mjcf::CompileMessageLine(message);
        line && *line >= 1 && *line <= map.size() && map[*line - 1]) {
      element = map[*line - 1]->Describe();
      element = element.substr(0, element.find(" at "));
    }
    for (const char* generated : {"\nElement", "\nObject"}) {
      if (const auto cut = message.find(generated); cut != std::string::npos) message.erase(cut);
    }
    throw InputError({mesh, 0}, "the converted model does not compile: " + message +
                                    (element.empty() ? "" : " (in " + element + ")"));
  }
}

int Convert(const ConvertArgs& args) {
  namespace fs = std::filesystem;
  CurrentInput() = args.mesh;
  convert::PropSpec spec;
  spec.mesh = fs::absolute(args.mesh).lexically_normal().string();
  const std::string stem = fs::path(args.out).stem().string();
  spec.name = stem.empty() ? "converted" : stem;
  spec.mode = *convert::ParsePropMode(args.mode);
  spec.mass = args.mass;
  spec.density = args.density;
  spec.decompose.threshold = args.threshold;
  spec.decompose.max_parts = args.max_parts;
  spec.decompose.resolution = args.resolution;
  spec.decompose.threads = args.threads;
  // Ctrl-C in graceful mode is polled by the decomposition's threads (an atomic load).
  spec.decompose.cancelled = [] { return StopSignal() != 0; };
  // Where nothing is being written (reading, the visual mesh's check, the decomposition), a
  // signal ends the process at once; writes (the cache, the parts) finish first.
  spec.decompose.interruptible = [](bool on) { SetImmediateExit(on); };
  const bool tty = isatty(fileno(stderr));
  int last_percent = -1;
  spec.decompose.progress = [&](double f, std::string_view stage) {
    const int percent = static_cast<int>(f * 100);
    if (percent == last_percent) return;
    last_percent = percent;
    if (tty) {
      std::fprintf(stderr, "\r[%3d%%] %-24.*s", percent, static_cast<int>(stage.size()),
                   stage.data());
      if (percent >= 100) std::fprintf(stderr, "\n");
    } else if (percent % 10 == 0) {
      std::fprintf(stderr, "[%3d%%] %.*s\n", percent, static_cast<int>(stage.size()), stage.data());
    }
  };
  CheckOutputs({{args.out, "-o"}}, {spec.mesh});
  if (const OutputTarget t = ResolveOutput(args.out); t.mode == OutputTarget::Mode::kInPlace) {
    throw InputError({args.out, 0}, "-o is " + t.kind +
                                        "; convert writes a model file with its parts in a "
                                        "folder beside it, so -o must name a regular file");
  }
  const fs::path out = fs::absolute(args.out);
  const std::string parts_dir = (out.parent_path() / (out.stem().string() + "_parts")).string();
  std::string cache = args.cache_dir.empty() ? convert::DefaultCacheDir() : args.cache_dir;
  if (args.no_cache) cache = (fs::temp_directory_path() / "urlab-convert-nocache").string();
  if (args.no_cache) fs::remove_all(cache);
  GracefulScope finish_writing;
  const auto t0 = std::chrono::steady_clock::now();
  // The parts go to a staging folder first: nothing of OUT is written (or replaced) until the
  // model has compiled.
  const std::string staging = parts_dir + ".partial";
  fs::remove_all(staging);
  convert::PropDocument prop;
  try {
    prop = convert::BuildPropDocument(spec, cache, staging);
    for (const std::string& line : prop.report) spdlog::info("{}", line);
    convert::ThrowIfCancelled(spec.decompose);
    CheckCompiles(prop, spec.mesh);
    convert::ThrowIfCancelled(spec.decompose);
  } catch (const convert::Cancelled&) {
    fs::remove_all(staging);
    if (last_percent >= 0 && tty) std::fprintf(stderr, "\n");
    return ExitCodeForSignal(StopSignal());  // leaving the graceful scope reports the signal
  } catch (...) {
    fs::remove_all(staging);
    throw;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  fs::remove_all(parts_dir);
  fs::rename(staging, parts_dir);
  prop.doc.root().Visit([&](document::Element& e) {
    const std::string file = e.GetOr("file", "");
    if (e.tag() == "mesh" && file.rfind(staging + "/", 0) == 0) {
      e.Set("file", parts_dir + file.substr(staging.size()));
    }
  });
  mjcf::WriteFile(prop.doc, out.string());  // paths relative to OUT.xml's folder
  std::cout << "wrote " << out.string() << " and " << prop.decomposition.parts.size()
            << " part meshes in " << parts_dir << "\n";
  std::cout << "parts " << prop.decomposition.parts.size() << "\nconcavity "
            << prop.decomposition.concavity << "\ncache " << (prop.cache_hit ? "hit" : "miss")
            << "\nseconds " << seconds << "\n";
  return 0;
}

}  // namespace

void RegisterConvertCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* cmd = app.add_subcommand(
      "convert",
      "Convex-decompose a mesh (STL, OBJ, PLY, glTF/GLB, FBX, DAE...) into a stand-alone MJCF "
      "model: visual mesh in group 2, convex parts (OUT_parts/partN.stl) in group 3. The visual "
      "mesh is checked with MuJoCo first (a flat or inconsistently oriented mesh fails in "
      "seconds); the model is compiled before anything is written. Ctrl-C stops the "
      "decomposition promptly, writes nothing and exits 130.");
  cmd->add_option("mesh", args->mesh, "mesh file")->required();
  cmd->add_option("-o,--output", args->out, "MJCF file to write")->required()->check(OutputPath());
  cmd->add_option("--threshold", args->threshold,
                  "concavity limit as a fraction of the bounding-box diagonal (default 0.05)")
      ->check(CLI::Range(1e-4, 1.0));
  cmd->add_option("--max-parts", args->max_parts, "at most this many parts (default 32)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--resolution", args->resolution,
                  "voxels along the longest side for the volume term (default 50)")
      ->check(CLI::Range(4, 400));
  cmd->add_option("--threads", args->threads, "worker threads (default: all cores)")
      ->check(CLI::Range(0, 256));
  cmd->add_option("--mode", args->mode, "static, dynamic (free joint) or mocap")
      ->check(CLI::IsMember({"static", "dynamic", "mocap"}));
  cmd->add_option("--mass", args->mass, "total mass in kg (parts share it by volume)")
      ->check(kFinitePositive);
  cmd->add_option("--density", args->density, "density in kg/m^3")->check(kFinitePositive);
  cmd->add_option("--cache-dir", args->cache_dir,
                  "decomposition cache (default $URLAB_CACHE_DIR or ~/.cache/urlab)");
  cmd->add_flag("--no-cache", args->no_cache, "decompose even when a cached result exists");
  cmd->callback([args, &exit_code] { exit_code = Convert(*args); });
}

}  // namespace urlab::app
