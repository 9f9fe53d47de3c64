// Command-line pieces the element benchmarks share (bench_elements,
// element_parts): comma-separated lists, the --laws and --modes values, and
// the UTC date stamped into their JSON.
#pragma once
#include <ctime>
#include <sstream>
#include <string>
#include <vector>

#include "material/Material.hpp"

namespace bench {

// "a,b,,c" -> {"a", "b", "c"}
inline std::vector<std::string> splitList(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string item; std::getline(ss, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

// --laws svk,snh; bad(message) is called (and must not return) on anything else.
template <class Bad>
std::vector<qdem::MaterialLaw> lawsFrom(const std::string& v, Bad&& bad) {
    std::vector<qdem::MaterialLaw> laws;
    for (const std::string& s : splitList(v)) {
        if (s == "svk") laws.push_back(qdem::MaterialLaw::SaintVenantKirchhoff);
        else if (s == "snh") laws.push_back(qdem::MaterialLaw::StableNeoHookean);
        else bad("--laws: 'svk' or 'snh', got '" + s + "'");
    }
    return laws;
}

// --modes viscous,elastic -> true for viscous.
template <class Bad>
std::vector<bool> modesFrom(const std::string& v, Bad&& bad) {
    std::vector<bool> viscous;
    for (const std::string& s : splitList(v)) {
        if (s == "viscous" || s == "elastic") viscous.push_back(s == "viscous");
        else bad("--modes: 'viscous' or 'elastic', got '" + s + "'");
    }
    return viscous;
}

inline std::string isoNow() {
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    return date;
}

}  // namespace bench
