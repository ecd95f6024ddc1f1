#pragma once
/// The one exception hierarchy of Quadrix. Messages name the thing at fault
/// (file, element, index, byte offset, the bad value). The CLI maps each kind
/// to a distinct exit code (tools/exit_codes.h).
#include <stdexcept>
#include <string>

namespace quadrix {

/// Base of every error Quadrix throws on purpose.
class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// A caller handed in something unusable: empty or degenerate geometry, NaN, bad options.
class InvalidInput : public Error {
public:
  using Error::Error;
};

/// A file could not be parsed or failed validation; the message names file and place.
class FormatError : public InvalidInput {
public:
  using InvalidInput::InvalidInput;
};

/// A file could not be opened, read or written (missing, permissions, disk full).
class IoError : public Error {
public:
  using Error::Error;
};

/// A numerical or external solver failed (fitting diverged, TetGen refused a cell).
class SolverError : public Error {
public:
  using Error::Error;
};

/// No usable OpenGL context, or a GL call/shader compile failed.
class GlError : public Error {
public:
  using Error::Error;
};

}  // namespace quadrix
