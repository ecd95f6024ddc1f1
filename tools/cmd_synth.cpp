// quadrix synth KIND -o FILE: small analytic models for tests and the demo, and the
// Marschner–Lobb test volume (`synth marschner-lobb -o ml.nhdr`, a NRRD for `convert volume`).
#include <filesystem>

#include <fmt/format.h>

#include "convert/volume.h"
#include "core/log.h"
#include "core/model_io.h"
#include "core/synth.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

constexpr const char* kMarschnerLobb = "marschner-lobb";
constexpr int kMarschnerLobbSamples = 41;  // the classic 41³ grid

}  // namespace

void add_synth(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("synth", "Write a small analytic model (or the Marschner–Lobb test volume)");
  struct Args {
    WriteModelOptions write;  // --encoding
    std::string kind, out;
    SynthOptions options;
  };
  auto a = std::make_shared<Args>();
  std::vector<std::string> kinds = synth_kinds();
  kinds.push_back(kMarschnerLobb);
  app->add_option("KIND", a->kind, "Model kind, or marschner-lobb for the volume")
      ->required()
      ->check(CLI::IsMember(kinds));
  app->add_option("-o,--out", a->out, "Output .qxm file (marschner-lobb: a .nhdr header, its .raw data beside it)")
      ->required();
  add_encoding_option(*app, a->write);
  app->add_option("--count", a->options.count, "Primitives (glyphs, slim-sphere; default: per kind)")
      ->check(number({.lo = 0, .hi = 50e6}))
      ->default_str("");
  app->add_option("--resolution", a->options.resolution,
                  "Grid cells per axis for hyperboloid1 and hyperboloid2 (default 10); samples per axis for "
                  "marschner-lobb (default 41)")
      ->check(number({.lo = 0, .hi = 512}))
      ->default_str("");
  app->add_option("--seed", a->options.seed, "Random seed (glyphs)")->check(non_negative());
  commands.push_back({app, [a](const CommonOptions&, Report& report) {
                        if (a->kind == kMarschnerLobb) {
                          if (std::filesystem::path(a->out).extension() != ".nhdr")
                            throw CLI::ValidationError("--out", fmt::format("marschner-lobb writes a NRRD header: "
                                                                            "name it FILE.nhdr, not '{}'", a->out));
                          const int n = a->options.resolution > 0 ? a->options.resolution : kMarschnerLobbSamples;
                          const Volume v = marschner_lobb_volume(n);
                          write_nrrd(v, a->out);
                          std::filesystem::path raw = a->out;
                          raw.replace_extension(".raw");
                          const auto [lo, hi] = v.range();
                          report.json["synth"] = {{"kind", a->kind}, {"out", a->out},     {"data", raw.string()},
                                                  {"dims", v.dims},  {"value_min", lo},   {"value_max", hi}};
                          report.summary = fmt::format("wrote {} and {} ({}³ samples over [-1, 1]³)", a->out, raw.string(), n);
                          return kOk;
                        }
                        Model m = synth_model(a->kind, a->options);
                        m.metadata["producer"] = command_line();
                        write_model(m, a->out, a->write);
                        report.json["synth"] = {{"kind", a->kind},     {"out", a->out},
                                                {"slim", m.slims.size()}, {"tet", m.tets.size()},
                                                {"glyph", m.glyphs.size()}};
                        report.summary = fmt::format("wrote {} ({} primitives)", a->out, m.size());
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
