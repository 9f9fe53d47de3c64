#include "SizeGrid.hpp"

#include <algorithm>
#include <cmath>

namespace qdem {

SizeGrid::SizeGrid(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double spacing, double cap,
                   std::size_t maxNodes)
    : cap_(cap) {
    double h = spacing;
    auto count = [&](double step) {
        double total = 1;
        for (int a = 0; a < 3; ++a) total *= std::floor((hi[a] - lo[a]) / step) + 3;
        return total;
    };
    while (count(h) > static_cast<double>(maxNodes)) h *= 1.25;
    h_ = h;
    for (int a = 0; a < 3; ++a) {
        lo_[a] = lo[a] - h;
        n_[a] = static_cast<std::size_t>(std::floor((hi[a] - lo[a]) / h)) + 3;
    }
    v_.assign(n_[0] * n_[1] * n_[2], static_cast<float>(cap));
}

std::array<double, 3> SizeGrid::node(std::size_t i, std::size_t j, std::size_t k) const {
    return {lo_[0] + h_ * static_cast<double>(i), lo_[1] + h_ * static_cast<double>(j),
            lo_[2] + h_ * static_cast<double>(k)};
}

void SizeGrid::range(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double pad,
                     std::array<std::size_t, 3>& first, std::array<std::size_t, 3>& last) const {
    for (int a = 0; a < 3; ++a) {
        const double f = std::ceil((lo[a] - pad - lo_[a]) / h_), l = std::floor((hi[a] + pad - lo_[a]) / h_);
        first[a] = static_cast<std::size_t>(std::clamp(f, 0.0, static_cast<double>(n_[a] - 1)));
        last[a] = static_cast<std::size_t>(std::clamp(l, 0.0, static_cast<double>(n_[a] - 1)));
    }
}

void SizeGrid::lower(std::size_t i, std::size_t j, std::size_t k, double size) {
    float& v = v_[index(i, j, k)];
    if (size < v) {
        v = static_cast<float>(size);
        seeded_ = true;
    }
}

void SizeGrid::grade(double gradation) {
    // The 13 neighbours before a node in raster order (forward sweep); the
    // backward sweep uses their mirror images.
    struct Step {
        int di, dj, dk;
        float w;
    };
    std::vector<Step> before;
    for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj)
            for (int dk = -1; dk <= 1; ++dk) {
                const bool earlier = di < 0 || (di == 0 && (dj < 0 || (dj == 0 && dk < 0)));
                if (earlier)
                    before.push_back({di, dj, dk,
                                      static_cast<float>(gradation * h_ * std::sqrt(double(di * di + dj * dj + dk * dk)))});
            }
    const long ni = static_cast<long>(n_[0]), nj = static_cast<long>(n_[1]), nk = static_cast<long>(n_[2]);
    auto relax = [&](long i, long j, long k, int sign) {
        float& v = v_[index(i, j, k)];
        for (const Step& s : before) {
            const long a = i + sign * s.di, b = j + sign * s.dj, c = k + sign * s.dk;
            if (a < 0 || b < 0 || c < 0 || a >= ni || b >= nj || c >= nk) continue;
            v = std::min(v, v_[index(a, b, c)] + s.w);
        }
    };
    for (long i = 0; i < ni; ++i)
        for (long j = 0; j < nj; ++j)
            for (long k = 0; k < nk; ++k) relax(i, j, k, 1);
    for (long i = ni - 1; i >= 0; --i)
        for (long j = nj - 1; j >= 0; --j)
            for (long k = nk - 1; k >= 0; --k) relax(i, j, k, -1);
}

double SizeGrid::at(double x, double y, double z) const {
    if (!seeded_) return cap_;
    const double p[3] = {x, y, z};
    std::size_t c[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        const double u = std::clamp((p[a] - lo_[a]) / h_, 0.0, static_cast<double>(n_[a] - 1) - 1e-9);
        c[a] = static_cast<std::size_t>(u);
        f[a] = u - static_cast<double>(c[a]);
    }
    double s = 0;
    for (int corner = 0; corner < 8; ++corner) {
        const std::size_t di = corner & 1, dj = corner >> 1 & 1, dk = corner >> 2 & 1;
        const double w = (di ? f[0] : 1 - f[0]) * (dj ? f[1] : 1 - f[1]) * (dk ? f[2] : 1 - f[2]);
        s += w * v_[index(c[0] + di, c[1] + dj, c[2] + dk)];
    }
    return std::min(s, cap_);
}

}  // namespace qdem
