// The checked-in malformed corpus (tests/data/malformed, run through the CLI by test_cli) read
// in-process by the readers its command goes through, every kind of it, so that
// `make test-sanitize` (ASan + UBSan) replays it deterministically.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "convert/balls.h"
#include "convert/ellipsoids_csv.h"
#include "convert/tetmesh_io.h"
#include "convert/volume.h"
#include "core/error.h"
#include "core/io/file.h"
#include "core/io/io.h"
#include "core/model_io.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;

// What the command of each kind reads, as test_cli runs it (tets with values4.txt, values on
// tet4.mesh). False for a kind the manifest does not know.
bool read_as(const std::string& kind, const fs::path& file, const fs::path& files) {
  if (kind == "info" || kind == "render") read_model(file);
  else if (kind == "quads") read_mesh(file);
  else if (kind == "fit") read_points(file);
  else if (kind == "volume") read_volume(file);
  else if (kind == "tets") read_vertex_values(files / "values4.txt", read_tet_mesh(file).vertices.size());
  else if (kind == "values") read_vertex_values(file, read_tet_mesh(files / "tet4.mesh").vertices.size());
  else if (kind == "skin") read_balls(file);
  else if (kind == "glyphs") read_ellipsoids_csv(file);
  else return false;
  return true;
}

// Every file either loads (the command refuses it later, e.g. too few points to fit) or throws one
// of core/error.h's errors naming the file, with the manifest's message fragment and no control
// bytes (the CLI escapes what it prints; the library's own messages must not need it). A crash,
// a sanitizer report or any other exception fails.
TEST(MalformedCorpus, EveryKindThroughItsReaders) {
  const fs::path root = fs::path(QUADRIX_TEST_DATA) / "malformed";
  std::ifstream manifest(root / "MANIFEST.tsv");
  ASSERT_TRUE(manifest) << root / "MANIFEST.tsv";
  std::map<std::string, std::pair<int, int>> by_kind;  // kind → (read, refused)
  std::size_t read = 0, refused = 0;
  for (std::string line; std::getline(manifest, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string file, kind, code, fragment;
    std::getline(fields, file, '\t'), std::getline(fields, kind, '\t'), std::getline(fields, code, '\t');
    std::getline(fields, fragment);
    SCOPED_TRACE(file + " (" + kind + ")");
    ++read, ++by_kind[kind].first;
    try {
      if (!read_as(kind, root / "files" / file, root / "files")) ADD_FAILURE() << "unknown kind '" << kind << "'";
    } catch (const Error& e) {
      ++refused, ++by_kind[kind].second;
      const std::string m = e.what();
      EXPECT_NE(m.find(file), std::string::npos) << "the message names no file: " << m;
      EXPECT_NE(m.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << m;
      for (const unsigned char ch : m) EXPECT_TRUE(ch >= 0x20 || ch == '\n') << "control byte in: " << io::echo(m);
    }
  }
  for (const auto& [kind, n] : by_kind) std::printf("malformed corpus: %-7s %3d files, %3d refused by the readers\n",
                                                     kind.c_str(), n.first, n.second);
  EXPECT_GE(read, 240u);
  EXPECT_EQ(by_kind.size(), 9u) << "a kind of the manifest is not replayed";
  EXPECT_GE(refused, read * 9 / 10) << refused << " of " << read << " refused by the readers";
}

}  // namespace
}  // namespace quadrix
