// A world's dynamic state as named byte arrays: what a restart needs to go on
// exactly where a run stopped (positions, velocities, contact histories,
// sleeping pieces, clocks, energy sums).  The mesh, materials and settings
// are not in it: the script builds the same scene again first.
#pragma once
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "../core/Errors.hpp"

namespace qdem {

struct WorldState {
    std::map<std::string, std::vector<uint8_t>> fields;

    // Untyped forms for the columns phases declare (Phase.hpp): n values of
    // elemSize bytes each.
    void putBytes(const std::string& name, const void* p, std::size_t n, std::size_t elemSize) {
        std::vector<uint8_t>& f = fields[name];
        f.resize(n * elemSize);
        if (n) std::memcpy(f.data(), p, n * elemSize);
    }
    void checkBytes(const std::string& name, std::size_t n, std::size_t elemSize) const {
        const auto it = fields.find(name);
        if (it == fields.end()) throw InputError("world state: field '" + name + "' is missing");
        if (it->second.size() != n * elemSize)
            throw InputError("world state: field '" + name + "' has " + std::to_string(it->second.size() / elemSize) +
                             " values, this world needs " + std::to_string(n) +
                             " (not the same scene: build the same pieces before loading)");
    }
    void getBytes(const std::string& name, void* p, std::size_t n, std::size_t elemSize) const {
        checkBytes(name, n, elemSize);
        if (n) std::memcpy(p, fields.find(name)->second.data(), n * elemSize);
    }

    template <class T>
    void put(const std::string& name, const T* p, std::size_t n) {
        std::vector<uint8_t>& f = fields[name];
        f.resize(n * sizeof(T));
        if (n) std::memcpy(f.data(), p, n * sizeof(T));
    }
    // Throws InputError naming the field unless it holds exactly n values of T.
    template <class T>
    void check(const std::string& name, std::size_t n) const {
        const auto it = fields.find(name);
        if (it == fields.end()) throw InputError("world state: field '" + name + "' is missing");
        if (it->second.size() != n * sizeof(T))
            throw InputError("world state: field '" + name + "' has " + std::to_string(it->second.size() / sizeof(T)) +
                             " values, this world needs " + std::to_string(n) +
                             " (not the same scene: build the same pieces before loading)");
    }
    // Copies field `name` into p[0..n).
    template <class T>
    void get(const std::string& name, T* p, std::size_t n) const {
        check<T>(name, n);
        if (n) std::memcpy(p, fields.find(name)->second.data(), n * sizeof(T));
    }
    template <class T>
    std::vector<T> getAll(const std::string& name) const {
        const auto it = fields.find(name);
        if (it == fields.end()) throw InputError("world state: field '" + name + "' is missing");
        std::vector<T> v(it->second.size() / sizeof(T));
        if (!v.empty()) std::memcpy(v.data(), it->second.data(), v.size() * sizeof(T));
        return v;
    }
};

}  // namespace qdem
