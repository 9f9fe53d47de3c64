// Minimum and median of repeated timings (the figures every benchmark here
// reports: the median to quote, the minimum as the machine's best).
#pragma once
#include <algorithm>
#include <vector>

struct Stats {
    std::vector<double> v;
    double min() const { return *std::min_element(v.begin(), v.end()); }
    double median() const {
        std::vector<double> s = v;
        std::sort(s.begin(), s.end());
        return s.size() % 2 ? s[s.size() / 2] : 0.5 * (s[s.size() / 2 - 1] + s[s.size() / 2]);
    }
};
