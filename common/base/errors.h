// Typed errors of the MeshMend core. Each message says what is wrong and what
// the user can do about it; the plugins show it as the filter's error message.
#pragma once

#include <stdexcept>
#include <string>

namespace meshmend {

// Base of every error the core throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The input violates a precondition that is not about topology: empty mesh,
// non-finite or out-of-range coordinates, a face index out of range, a bad option.
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

// The input's topology does not allow the operation (non-manifold, open where
// a closed mesh is needed, inconsistently oriented, ...).
class TopologyError : public Error {
 public:
  using Error::Error;
};

// The operation reached one of its work bounds (candidate pairs, rounds,
// exact-arithmetic evaluations) and stopped; the message names the bound
// and what to try. Nothing was changed.
class WorkLimitError : public Error {
 public:
  using Error::Error;
};

// What the operation computed does not meet its stated contract (checked
// exactly on what it would store): the message says what does not hold and
// what to try. Nothing was changed.
class ContractError : public Error {
 public:
  using Error::Error;
};

// The user's progress callback asked to stop.
class CancelledError : public Error {
 public:
  CancelledError() : Error("cancelled by the user") {}
};

}  // namespace meshmend
