// Minimum, median and maximum of repeated timings (the figures every benchmark
// here reports: the median to quote, the minimum as the machine's best, the
// maximum to show the spread).
#pragma once
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

struct Stats {
    std::vector<double> v;
    double min() const { return *std::min_element(v.begin(), v.end()); }
    double max() const { return *std::max_element(v.begin(), v.end()); }
    double median() const {
        std::vector<double> s = v;
        std::sort(s.begin(), s.end());
        return s.size() % 2 ? s[s.size() / 2] : 0.5 * (s[s.size() / 2 - 1] + s[s.size() / 2]);
    }
    // {"n": .., "min": .., "median": .., "max": ..}, or null without a value
    // (nothing measured is written as nothing, never as a zero).
    std::string json(const char* fmt = "%.4g") const {
        if (v.empty()) return "null";
        auto num = [&](double x) {
            char b[64];
            std::snprintf(b, sizeof b, fmt, x);
            return std::string(b);
        };
        return "{\"n\": " + std::to_string(v.size()) + ", \"min\": " + num(min()) + ", \"median\": " + num(median()) +
               ", \"max\": " + num(max()) + "}";
    }
};
