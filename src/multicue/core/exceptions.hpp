#pragma once
/// \file Typed exceptions. Every message names the bad value, file or parameter.
///
/// The CLI maps InvalidArgument to exit code 2 (usage error) and every other Error to 1 (data
/// error).

#include <stdexcept>
#include <string>

namespace multicue {

/// Base of every exception multicue throws.
class Error : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// A parameter or argument is out of its domain (`radius must be > 0, got -0.1`).
class InvalidArgument : public Error {
  public:
    using Error::Error;
};

/// A file could not be opened, read or written.
class IoError : public Error {
  public:
    using Error::Error;
};

/// A file was readable but its content is malformed (bad header, truncated data, unsupported type).
class FormatError : public IoError {
  public:
    using IoError::IoError;
};

/// Input data violates a precondition of an algorithm (no valid points, mismatched sizes).
class DataError : public Error {
  public:
    using Error::Error;
};

}  // namespace multicue
