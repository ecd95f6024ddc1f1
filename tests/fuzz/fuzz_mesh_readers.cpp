// libFuzzer target for the I/O kit's text and binary mesh/point readers (one per build:
// -DQUADRIX_FUZZ_READER=off|obj|stl|ply|xyz). Every input must either parse or throw one of
// core/error.h's errors; a crash, sanitizer report or other exception is a finding.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/error.h"
#include "core/io/formats.h"

#define QUADRIX_STR2(x) #x
#define QUADRIX_STR(x) QUADRIX_STR2(x)

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const std::string_view reader = QUADRIX_STR(QUADRIX_FUZZ_READER);
  try {
    if (reader == "off") quadrix::io::read_off(bytes, "fuzz.off");
    else if (reader == "obj") quadrix::io::read_obj(bytes, "fuzz.obj");
    else if (reader == "stl") quadrix::io::read_stl(bytes, "fuzz.stl");
    else if (reader == "ply") quadrix::io::read_ply(std::string(bytes), "fuzz.ply");
    else if (reader == "xyz") quadrix::io::read_xyz(bytes, "fuzz.xyz", false);
  } catch (const quadrix::Error&) {
  }
  return 0;
}
