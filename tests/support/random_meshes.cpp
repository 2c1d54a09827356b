#include "support/random_meshes.hpp"

#include <cmath>
#include <map>
#include <random>

namespace toposimp::testing {
namespace {

void grid_faces(mesh::Mesh& m, std::uint32_t first, int n, bool flip_diagonals, std::mt19937_64& random) {
    auto id = [&](int i, int j) { return first + static_cast<std::uint32_t>(j * (n + 1) + i); };
    std::bernoulli_distribution coin(0.5);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const std::uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
            if (flip_diagonals && coin(random)) {
                m.faces.push_back({a, b, d});
                m.faces.push_back({b, c, d});
            } else {
                m.faces.push_back({a, b, c});
                m.faces.push_back({a, c, d});
            }
        }
    }
}

}  // namespace

mesh::Mesh noisy_sphere(int level, double noise, std::uint64_t seed, Point3 center) {
    mesh::Mesh m;
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    m.points = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    m.faces = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
               {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
               {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (int l = 0; l < level; ++l) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
        auto mid = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            if (auto it = middle.find(key); it != middle.end()) return it->second;
            const Point3 p = m.points[a], q = m.points[b];
            m.points.push_back({(p.x + q.x) / 2, (p.y + q.y) / 2, (p.z + q.z) / 2});
            return middle[key] = static_cast<std::uint32_t>(m.points.size() - 1);
        };
        std::vector<mesh::Face> faces;
        for (const mesh::Face& f : m.faces) {
            const std::uint32_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
            faces.push_back({f[0], ab, ca});
            faces.push_back({f[1], bc, ab});
            faces.push_back({f[2], ca, bc});
            faces.push_back({ab, bc, ca});
        }
        m.faces = std::move(faces);
    }
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> jitter(-noise, noise);
    for (Point3& p : m.points) {
        const double r = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
        const double s = (1.0 + jitter(random)) / r;
        p = {center.x + p.x * s, center.y + p.y * s, center.z + p.z * s};
    }
    return m;
}

mesh::Mesh noisy_heightfield(int n, double noise, std::uint64_t seed) {
    mesh::Mesh m;
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> jitter(-noise, noise);
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
            const double height = 3.0 * std::sin(i * 0.21) * std::cos(j * 0.17) + jitter(random);
            m.points.push_back({static_cast<double>(i), static_cast<double>(j), height});
        }
    }
    grid_faces(m, 0, n, true, random);
    return m;
}

mesh::Mesh near_sheets(int n, int ulps, std::uint64_t seed) {
    mesh::Mesh m;
    for (int sheet = 0; sheet < 2; ++sheet) {
        const auto first = static_cast<std::uint32_t>(m.points.size());
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                // Heights in [4, 8): one binade, so the lift is exactly `ulps` ulps everywhere.
                double z = 6.0 + 1.5 * std::sin(i * 0.7) * std::sin(j * 0.5);
                if (sheet == 1) {
                    for (int k = 0; k < ulps; ++k) z = std::nextafter(z, 8.0);
                }
                m.points.push_back({static_cast<double>(i), static_cast<double>(j), z});
            }
        }
        // The same diagonals in both sheets: the upper surface is then strictly above the lower.
        std::mt19937_64 diagonals(seed);
        grid_faces(m, first, n, true, diagonals);
    }
    return m;
}

mesh::Mesh folded_strip(int length, double gap, std::uint64_t seed) {
    // A 2-wide strip zig-zagging in x: along +x at z = 0, back along −x at z = gap, along +x at
    // z = 2·gap, joined at the folds by vertical steps.
    mesh::Mesh m;
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> jitter(-0.2 * gap, 0.2 * gap);
    const int layers = 3;
    // The strip's centre line: (x, z) positions in order.
    std::vector<std::pair<double, double>> line;
    for (int layer = 0; layer < layers; ++layer) {
        for (int s = 0; s <= length; ++s) {
            const double x = layer % 2 == 0 ? s : length - s;
            line.emplace_back(x, layer * gap);
        }
    }
    for (std::size_t k = 0; k < line.size(); ++k) {
        for (int w = 0; w <= 2; ++w) {
            const bool fold = k % static_cast<std::size_t>(length + 1) == 0 || k % static_cast<std::size_t>(length + 1) == static_cast<std::size_t>(length);
            m.points.push_back({line[k].first, static_cast<double>(w), line[k].second + (fold ? 0.0 : jitter(random))});
        }
    }
    for (std::size_t k = 0; k + 1 < line.size(); ++k) {
        for (int w = 0; w < 2; ++w) {
            const auto a = static_cast<std::uint32_t>(3 * k + w), b = static_cast<std::uint32_t>(3 * (k + 1) + w);
            // Along a layer, or the vertical step at a fold: the same two triangles.
            m.faces.push_back({a, b, b + 1});
            m.faces.push_back({a, b + 1, a + 1});
        }
    }
    return m;
}

}  // namespace toposimp::testing
