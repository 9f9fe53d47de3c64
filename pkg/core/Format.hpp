// Tiny helper to build error messages with numbers in them.
#pragma once
#include <sstream>
#include <string>

namespace qdem {

template <class... Args>
std::string cat(const Args&... args) {
    std::ostringstream os;
    os.precision(6);
    (os << ... << args);
    return os.str();
}

}  // namespace qdem
