// quadrix convert volume VOLUME --iso V -o FILE: quadratic iso-surface patches clipped by the
// tetrahedra of the grid ([Stoll06] §5.1.2); or of a given tetrahedral mesh with per-vertex values
// (--tets FILE --values FILE). Registered under the `convert` group by add_convert_volume (called
// from tools/cmd_convert.cpp).
#include <cstdio>
#include <iostream>
#include <tuple>

#include <fmt/format.h>

#include "convert/tetmesh_io.h"
#include "convert/volume.h"
#include "convert/volume_stats.h"
#include "core/error.h"
#include "core/log.h"
#include "core/model_io.h"
#include "tools/cli.h"

namespace quadrix::cli {
namespace {

// Without --iso: Otsu's threshold of the values (convert/volume_stats.h), said on stderr and
// recorded. Returns the iso-value and its source.
std::pair<double, std::string> suggested_iso(const Volume& values, const CommonOptions& common) {
  const VolumeStats s = volume_stats(values);
  if (s.suggestions.empty())
    throw InvalidInput(fmt::format("{}: constant data ({:g}): no iso-value to suggest", values.source, s.min));
  const IsoSuggestion& g = s.suggestions.front();
  if (!common.quiet)
    std::cerr << fmt::format("quadrix: no --iso given: using {:.6g}, Otsu's threshold ({} of the values {:.6g} – "
                             "{:.6g}, {:.1f} % below; quadrix info lists more)\n",
                             g.value, values.source, s.min, s.max, 100.0 * g.below);
  return {g.value, g.method};
}


// "A,B,C" of three numbers, each finite and within range. \throws CLI::ValidationError.
template <typename T>
std::array<T, 3> parse_triple(const std::string& text, const char* option, NumberRange range) {
  std::array<T, 3> v{};
  std::string rest = text;
  for (int a = 0; a < 3; ++a) {
    const auto comma = rest.find(',');
    std::string item = rest.substr(0, comma);
    if (const std::string why = number(range)(item); !why.empty())
      throw CLI::ValidationError(option, fmt::format("'{}': {}", text.substr(0, 80), why));
    try {
      std::size_t used = 0;
      if constexpr (std::is_integral_v<T>) v[a] = static_cast<T>(std::stoll(item, &used));
      else v[a] = static_cast<T>(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw CLI::ValidationError(option, fmt::format("expected three comma-separated numbers, got '{}'", text));
    }
    if ((comma == std::string::npos) != (a == 2))
      throw CLI::ValidationError(option, fmt::format("expected three comma-separated numbers, got '{}'", text));
    if (comma != std::string::npos) rest = rest.substr(comma + 1);
  }
  return v;
}

// convert volume --tets MESH --values FILE. Args: the command's option struct.
template <typename Args>
ExitCode run_tets(const Args& a, const CommonOptions& common, Report& report) {
  if (a.tets.empty() || a.values.empty()) throw CLI::ValidationError("--tets", "--tets and --values go together");
  if (!a.volume.empty() || !a.synth.empty())
    throw CLI::ValidationError("--tets", "give either a VOLUME file, --synth or --tets, not several");
  if (!a.dims.empty() || !a.type.empty() || !a.spacing.empty() || !a.write_volume.empty())
    throw CLI::ValidationError("--tets", "--dims, --type, --spacing and --write-volume are for grid volumes");
  const double t0 = report.elapsed();
  const TetMesh mesh = read_tet_mesh(a.tets);
  const std::vector<double> values = read_vertex_values(a.values, mesh.vertices.size());
  const double read_seconds = report.elapsed() - t0;
  VolumeIsoOptions o;
  o.iso = a.iso;
  std::string iso_source = "--iso";
  if (!a.has_iso) {
    Volume list;
    list.source = a.values;
    list.values.assign(values.begin(), values.end());
    std::tie(o.iso, iso_source) = suggested_iso(list, common);
  }
  o.linear = a.linear;
  if (!a.colour.empty()) o.colour = parse_rgb(a.colour);
  Progress progress("volume", progress_allowed(common));
  o.progress = progress.callback();
  const double t1 = report.elapsed();
  VolumeConversion conv = convert_tet_mesh(mesh, values, o);
  const double seconds = report.elapsed() - t1;
  const char* midpoints = a.linear ? "none" : "hermite-quadratic-fit";
  auto& meta = conv.model.metadata;
  meta["producer"] = command_line();
  meta["iso_source"] = iso_source;
  meta["source"] = a.tets;
  meta["values"] = a.values;
  meta["iso"] = fmt::format("{:.17g}", o.iso);
  meta["mesh"] = fmt::format("{} vertices, {} tetrahedra", mesh.vertices.size(), mesh.tets.size());
  meta["patches"] = a.linear ? "linear" : "quadratic";
  meta["reconstruction"] = midpoints;
  meta["value_range"] = fmt::format("{:g},{:g}", conv.value_min, conv.value_max);
  write_model(conv.model, a.out, a.write);
  report.json["convert"] = {{"kind", "volume"},
                            {"tets_file", a.tets},
                            {"values_file", a.values},
                            {"out", a.out},
                            {"vertices", mesh.vertices.size()},
                            {"iso", o.iso},
                            {"iso_source", iso_source},
                            {"value_min", conv.value_min},
                            {"value_max", conv.value_max},
                            {"linear", a.linear},
                            {"reconstruction", midpoints},
                            {"cells", conv.cells},
                            {"cells_visited", conv.cells_visited},
                            {"tets_tested", conv.tets_tested},
                            {"linear_gradients", conv.linear_gradients},
                            {"tets", conv.model.tets.size()},
                            {"read_seconds", read_seconds},
                            {"convert_seconds", seconds}};
  report.summary = fmt::format("wrote {}: {} tet patches from a mesh of {} vertices and {} tetrahedra ({:.3f} s converting)", a.out,
            conv.model.tets.size(), mesh.vertices.size(), mesh.tets.size(), seconds);
  return kOk;
}

}  // namespace

void add_convert_volume(CLI::App& convert, Commands& commands) {
  auto* app = convert.add_subcommand(
      "volume", "Volume (.nhdr/.nrrd, .inr[.gz], raw; or a .mesh/.node tet mesh with --values) to quadratic "
                "iso-surface patches clipped by tetrahedra");
  struct Args {
    WriteModelOptions write;  // --encoding
    std::string volume, out, dims, type, spacing, colour, reconstruction = "catmull-rom", synth, write_volume, tets,
        values;
    double iso = 0;
    bool has_iso = false;  // --iso given; else Otsu's threshold
    bool big_endian = false, linear = false;
    std::size_t header_bytes = 0;
    int grid = 41;
  };
  auto a = std::make_shared<Args>();
  app->add_option("VOLUME", a->volume, "Input volume: .nhdr/.nrrd, .inr/.inr.gz, or raw with --dims and --type");
  app->add_option("--iso", a->iso, "Iso-value V (strictly inside the data range; default: Otsu's threshold of the data, "
                                  "as quadrix info suggests)")
      ->check(finite())
      ->default_str("");
  app->add_option("-o,--out", a->out, "Output .qxm file")->required()->check(qxm_output());
  add_encoding_option(*app, a->write);
  app->add_option("--dims", a->dims, "Raw volume: samples per axis X,Y,Z (x fastest), each in [1, 2^30]");
  app->add_option("--type", a->type, "Raw volume: uint8|int8|uint16|int16|uint32|int32|float|double");
  app->add_flag("--big-endian", a->big_endian, "Raw volume: big-endian samples (default little)");
  app->add_option("--spacing", a->spacing, "Raw volume: voxel spacing SX,SY,SZ, each finite and > 0 (default 1,1,1)");
  app->add_option("--header-bytes", a->header_bytes, "Raw volume: bytes to skip at the start of the file")->check(non_negative());
  app->add_option("--reconstruction", a->reconstruction,
                  "Edge-midpoint values: catmull-rom (interpolating, C1; default) or trilinear")
      ->check(CLI::IsMember({"catmull-rom", "trilinear"}));
  app->add_flag("--linear", a->linear, "Linear patches instead (marching tetrahedra: planes clipped by the tetrahedra)");
  app->add_option("--colour", a->colour, "Constant colour R,G,B (0..255) for every patch");
  app->add_option("--synth", a->synth, "Use an analytic volume instead of VOLUME: marschner-lobb")
      ->check(CLI::IsMember({"marschner-lobb"}));
  app->add_option("--grid", a->grid, "Samples per axis of the --synth volume (default 41)")->check(number({.lo = 2, .hi = 1024}));
  app->add_option("--write-volume", a->write_volume, "Also write the input volume as NRRD (FILE.nhdr + FILE.raw)");
  app->add_option("--tets", a->tets,
                  "Use a tetrahedral mesh instead of VOLUME: Medit .mesh or TetGen .node/.ele (needs --values)");
  app->add_option("--values", a->values, "Per-vertex values of the --tets mesh: one number per vertex, # comments");
  commands.push_back({app, [a, app](const CommonOptions& common, Report& report) {
                        a->has_iso = app->count("--iso") > 0;
                        if (!a->tets.empty() || !a->values.empty()) return run_tets(*a, common, report);
                        if (a->synth.empty() == a->volume.empty())
                          throw CLI::ValidationError("VOLUME", "give either a VOLUME file, --synth or --tets");
                        std::optional<RawVolumeLayout> raw;
                        if (!a->dims.empty() || !a->type.empty()) {
                          if (a->dims.empty() || a->type.empty())
                            throw CLI::ValidationError("--dims", "raw volumes need both --dims and --type");
                          RawVolumeLayout l;
                          l.dims = parse_triple<int>(a->dims, "--dims", {.lo = 1, .hi = 1 << 30});
                          l.type = parse_voxel_type(a->type);
                          l.big_endian = a->big_endian;
                          l.header_bytes = a->header_bytes;
                          if (!a->spacing.empty()) {
                            const auto s = parse_triple<double>(a->spacing, "--spacing", {.lo = 0, .open_lo = true});
                            l.spacing = Eigen::Vector3d(s[0], s[1], s[2]);
                          }
                          raw = l;
                        }
                        const double t0 = report.elapsed();
                        const Volume volume =
                            a->synth.empty() ? read_volume(a->volume, raw) : marschner_lobb_volume(a->grid);
                        const double read_seconds = report.elapsed() - t0;
                        if (!a->write_volume.empty()) write_nrrd(volume, a->write_volume);
                        VolumeIsoOptions o;
                        o.iso = a->iso;
                        std::string iso_source = "--iso";
                        if (!a->has_iso) std::tie(o.iso, iso_source) = suggested_iso(volume, common);
                        o.reconstruction =
                            a->reconstruction == "trilinear" ? Reconstruction::trilinear : Reconstruction::catmull_rom;
                        o.linear = a->linear;
                        if (!a->colour.empty()) o.colour = parse_rgb(a->colour);
                        Progress progress("volume", progress_allowed(common));
                        o.progress = progress.callback();
                        const double t1 = report.elapsed();
                        VolumeConversion conv = convert_volume(volume, o);
                        const double seconds = report.elapsed() - t1;
                        const std::string input = a->synth.empty() ? a->volume : fmt::format("{} {}^3", a->synth, a->grid);
                        auto& meta = conv.model.metadata;
                        meta["producer"] = command_line();
                        meta["source"] = input;
                        meta["iso"] = fmt::format("{:.17g}", o.iso);
                        meta["iso_source"] = iso_source;
                        meta["grid"] = fmt::format("{}x{}x{}", volume.dims[0], volume.dims[1], volume.dims[2]);
                        meta["spacing"] = fmt::format("{:g},{:g},{:g}", volume.spacing.x(), volume.spacing.y(),
                                                      volume.spacing.z());
                        meta["patches"] = a->linear ? "linear" : "quadratic";
                        meta["reconstruction"] = a->linear ? "none" : a->reconstruction;
                        meta["value_range"] = fmt::format("{:g},{:g}", conv.value_min, conv.value_max);
                        write_model(conv.model, a->out, a->write);
                        report.json["convert"] = {{"kind", "volume"},
                                                  {"volume", input},
                                                  {"out", a->out},
                                                  {"dims", volume.dims},
                                                  {"iso", o.iso},
                                                  {"iso_source", iso_source},
                                                  {"value_min", conv.value_min},
                                                  {"value_max", conv.value_max},
                                                  {"linear", a->linear},
                                                  {"reconstruction", a->linear ? "none" : a->reconstruction},
                                                  {"cells", conv.cells},
                                                  {"cells_visited", conv.cells_visited},
                                                  {"tets_tested", conv.tets_tested},
                                                  {"tets", conv.model.tets.size()},
                                                  {"read_seconds", read_seconds},
                                                  {"convert_seconds", seconds}};
                        report.summary = fmt::format("wrote {}: {} tet patches from a {}x{}x{} volume ({} of {} cells near V) ({:.3f} s converting)",
                                  a->out, conv.model.tets.size(), volume.dims[0], volume.dims[1], volume.dims[2],
                                  conv.cells_visited, conv.cells, seconds);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
