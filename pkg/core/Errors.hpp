// Error types of the core.  The Python bindings translate InputError to
// ValueError and StabilityError to qdem.StabilityError, so a user sees a clear
// message naming the problem instead of a crash.
#pragma once
#include <stdexcept>
#include <string>

namespace qdem {

// Bad mesh, bad parameter, NaN in the input: the caller must fix its data.
struct InputError : std::invalid_argument {
    using std::invalid_argument::invalid_argument;
};

// A requested time step or state that the explicit scheme cannot integrate.
struct StabilityError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace qdem
