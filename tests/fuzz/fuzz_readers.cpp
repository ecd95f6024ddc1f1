// libFuzzer targets for every reader, in one binary: the reader is named by the program's name
// (fuzz_NAME, a hard link per reader, see tools/fuzz.sh) or by QUADRIX_FUZZ_READER=NAME.
// In-memory readers get the bytes; path-based readers get them through a file of the right
// extension in a per-process folder. Every input must either parse or throw one of
// core/error.h's errors; a crash, a sanitizer report or another exception is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

#include "convert/balls.h"
#include "convert/ellipsoids_csv.h"
#include "convert/tetmesh_io.h"
#include "convert/volume.h"
#include "core/error.h"
#include "core/image.h"
#include "core/implicit/expression.h"
#include "core/io/formats.h"
#include "core/model_io.h"

namespace {

namespace fs = std::filesystem;

// The folder the path-based readers' inputs are written to: removed when the fuzzer exits (at
// -max_total_time or -runs; a crash leaves it, with the input beside the crash file).
struct Folder {
  fs::path path = fs::temp_directory_path() / ("quadrix-fuzz-" + std::to_string(::getpid()));
  Folder() { fs::create_directories(path); }
  ~Folder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

const fs::path& folder() {
  static const Folder dir;
  return dir.path;
}

fs::path put(const std::string& name, std::string_view bytes) {
  const fs::path p = folder() / name;
  std::FILE* f = std::fopen(p.c_str(), "wb");
  if (!f) std::abort();
  if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) std::abort();
  std::fclose(f);
  return p;
}

// Two files from one input: the part before the first "@@\n" and the part after it.
std::pair<std::string_view, std::string_view> split(std::string_view bytes) {
  const auto at = bytes.find("@@\n");
  if (at == std::string_view::npos) return {bytes, {}};
  return {bytes.substr(0, at), bytes.substr(at + 3)};
}

const char* const kReaders[] = {"off", "obj", "stl", "ply", "xyz", "pts", "qxm", "slim2t", "mesh", "tetgen", "values",
                                "nrrd", "nhdr", "inr", "inrgz", "cin", "pdb", "csv", "png", "pfm", "implicit"};
std::string_view reader;  // one of kReaders, set once before the first input

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  std::string_view name;
  if (const char* env = std::getenv("QUADRIX_FUZZ_READER")) name = env;
  else if (*argc > 0) {
    name = (*argv)[0];
    if (const auto slash = name.rfind('/'); slash != std::string_view::npos) name.remove_prefix(slash + 1);
    if (name.starts_with("fuzz_")) name.remove_prefix(5);
  }
  for (const char* r : kReaders)
    if (name == r) reader = r;
  if (reader.empty()) {
    std::fprintf(stderr, "fuzz_readers: run as fuzz_NAME or with QUADRIX_FUZZ_READER=NAME, NAME one of:");
    for (const char* r : kReaders) std::fprintf(stderr, " %s", r);
    std::fprintf(stderr, "\n");
    std::exit(2);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace quadrix;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    if (reader == "off") io::read_off(bytes, "fuzz.off");
    else if (reader == "obj") io::read_obj(bytes, "fuzz.obj");
    else if (reader == "stl") io::read_stl(bytes, "fuzz.stl");
    else if (reader == "ply") io::read_ply(std::string(bytes), "fuzz.ply");
    else if (reader == "xyz") io::read_xyz(bytes, "fuzz.xyz", false);
    else if (reader == "pts") io::read_xyz(bytes, "fuzz.pts", true);
    else if (reader == "qxm") read_model(put("fuzz.qxm", bytes));
    else if (reader == "slim2t") read_slim2t(put("fuzz.slim2t", bytes));
    else if (reader == "png") read_png(put("fuzz.png", bytes));
    else if (reader == "pfm") read_pfm(put("fuzz.pfm", bytes));
    else if (reader == "implicit") implicit::Expression::parse(bytes);
    else if (reader == "mesh") read_tet_mesh(put("fuzz.mesh", bytes));
    else if (reader == "tetgen") {  // NODE@@\nELE
      const auto [node, ele] = split(bytes);
      put("fuzz.ele", ele);
      read_tet_mesh(put("fuzz.node", node));
    } else if (reader == "values") read_vertex_values(put("fuzz.txt", bytes), 8);
    else if (reader == "nrrd") read_volume(put("fuzz.nrrd", bytes));
    else if (reader == "nhdr") {  // NHDR@@\nDATA, the data file named "fuzz.raw" or "fuzz.raw.gz"
      const auto [head, body] = split(bytes);
      put("fuzz.raw", body);
      read_volume(put("fuzz.nhdr", head));
    } else if (reader == "inr") read_volume(put("fuzz.inr", bytes));
    else if (reader == "inrgz") read_volume(put("fuzz.inr.gz", bytes));
    else if (reader == "cin") read_balls(put("fuzz.cin", bytes), {});
    else if (reader == "pdb") read_balls(put("fuzz.pdb", bytes), {});
    else if (reader == "csv") read_ellipsoids_csv(put("fuzz.csv", bytes));
    else std::abort();  // a reader this target does not know
  } catch (const quadrix::Error&) {
  }
  return 0;
}
