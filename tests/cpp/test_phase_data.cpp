// The phases reach only the data they declare (pkg/step/Phase.hpp): each
// phase class is built from its nested Data alone, and no source of
// pkg/phases names World (so none can reach into the world past its Data).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <type_traits>

#include "phases/ElementPhase.hpp"
#include "phases/IntegrationPhase.hpp"
#include "phases/ObstaclePhase.hpp"
#include "phases/PieceContactPhase.hpp"
#include "phases/SleepPhase.hpp"
#include "phases/SpherePhase.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

// A phase is constructible from its Data and from nothing else of the world.
template <class P>
constexpr bool builtFromItsDataOnly() {
    return std::is_constructible_v<P, const typename P::Data&> && !std::is_constructible_v<P, World&> &&
           !std::is_default_constructible_v<P>;
}

// The source without its comments and string literals.
std::string code(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    static const std::regex comments(R"(//[^\n]*|/\*[\s\S]*?\*/|"(\\.|[^"\\])*")");
    return std::regex_replace(text, comments, " ");
}

}  // namespace

TEST(PhaseData, EveryPhaseIsBuiltFromItsDeclaredDataOnly) {
    static_assert(builtFromItsDataOnly<ObstaclePhase>());
    static_assert(builtFromItsDataOnly<PieceContactPhase>());
    static_assert(builtFromItsDataOnly<SpherePhase>());
    static_assert(builtFromItsDataOnly<ElementPhase>());
    static_assert(builtFromItsDataOnly<IntegrationPhase>());
    static_assert(builtFromItsDataOnly<SleepPhase>());
    SUCCEED();
}

TEST(PhaseData, NoPhaseSourceNamesTheWorld) {
    const std::filesystem::path dir = std::filesystem::path(QDEM_SOURCE_DIR) / "pkg" / "phases";
    ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir;
    const std::regex world(R"(\bWorld\b|World\.hpp)");
    int files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
        const auto ext = e.path().extension();
        if (ext != ".cpp" && ext != ".hpp") continue;
        ++files;
        const std::string c = code(e.path());
        std::smatch m;
        EXPECT_FALSE(std::regex_search(c, m, world))
            << e.path().filename() << " names the World (" << m.str() << "): a phase reads only its Data";
    }
    EXPECT_GE(files, 12);  // the phases' headers and sources were found
}
