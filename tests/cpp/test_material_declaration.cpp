// Materials are declared once (QDEM_MATERIAL_FIELDS, QDEM_MATERIAL_LAWS in
// pkg/material/Material.hpp): the struct's defaults, validate(), lawName and
// the law dispatch all follow the lists.
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "core/Errors.hpp"
#include "element/MaterialLaw.hpp"

using namespace qdem;

namespace {

// A value the range refuses, just outside an end (or non-finite).
std::vector<double> refused(const MaterialRange& r) {
    std::vector<double> v{NAN, INFINITY, -INFINITY};
    if (std::isfinite(r.lo)) v.push_back(r.loOpen ? r.lo : std::nextafter(r.lo, -INFINITY));
    if (std::isfinite(r.hi)) v.push_back(r.hiOpen ? r.hi : std::nextafter(r.hi, INFINITY));
    return v;
}

std::string refusal(const Material& m) {
    try {
        m.validate();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(MaterialDeclaration, EveryFieldHasItsDefaultAndIsValidated) {
    const Material defaults;
    EXPECT_EQ(refusal(defaults), "");
    std::set<std::string> names;
    for (const MaterialField& f : kMaterialFields) {
        EXPECT_TRUE(names.insert(f.name).second) << f.name << " declared twice";
        EXPECT_EQ(defaults.*f.member, f.def) << f.name;
        EXPECT_TRUE(f.range.allows(f.def)) << f.name << ": the default is outside its own range";
        EXPECT_NE(std::string(f.doc), "") << f.name;
        for (double bad : refused(f.range)) {
            Material m;
            m.*f.member = bad;
            const std::string msg = refusal(m);
            // Names the field and the value, and says what it must be.
            EXPECT_EQ(msg.rfind(std::string("QdemMat: ") + f.name + "=", 0), 0u) << msg;
            EXPECT_NE(msg.find(" is invalid: " + f.range.rule()), std::string::npos) << msg;
        }
    }
}

TEST(MaterialDeclaration, RulesSayWhatAValueMustBe) {
    EXPECT_EQ(MaterialRange::above(0).rule(), "must be a number > 0");
    EXPECT_EQ(MaterialRange::atLeast(0).rule(), "must be a number >= 0");
    EXPECT_EQ(MaterialRange::between(-1, 0.5, true, true).rule(), "must be a number in (-1, 0.5)");
    EXPECT_EQ(MaterialRange::between(0, 1, true, false).rule(), "must be a number in (0, 1]");
    Material m;
    m.poisson = 0.5;
    EXPECT_EQ(refusal(m), "QdemMat: poisson=0.5 is invalid: must be a number in (-1, 0.5)");
}

TEST(MaterialDeclaration, EveryLawIsNamedAndDispatchedToItsOwnClass) {
    std::set<std::string> names;
    int expected = 0;
    for (MaterialLaw tag : kMaterialLaws) {
        EXPECT_EQ(static_cast<int>(tag), expected++) << "law values follow the list";
        const std::string name = lawName(tag);
        EXPECT_NE(name, "unknown");
        EXPECT_TRUE(names.insert(name).second) << name << " named twice";
        MaterialLaw back{};
        ASSERT_TRUE(lawFromName(name, back)) << name;
        EXPECT_EQ(back, tag);
        EXPECT_NE(lawRule().find("'" + name + "'"), std::string::npos);
        Material m;
        m.law = tag;
        EXPECT_EQ(refusal(m), "") << name;
        // withLaw hands over the class declared for this tag.
        const MaterialLaw dispatched = withLaw(m, [](const auto& law) { return std::decay_t<decltype(law)>::kTag; });
        EXPECT_EQ(dispatched, tag) << name;
    }
    EXPECT_EQ(Material().law, kMaterialLaws[0]) << "the first law is the default";
    MaterialLaw none{};
    EXPECT_FALSE(lawFromName("neoHooke", none));
    Material m;
    m.law = static_cast<MaterialLaw>(std::size(kMaterialLaws));
    EXPECT_EQ(refusal(m), "QdemMat: law=" + std::to_string(std::size(kMaterialLaws)) + " is invalid: " + lawRule());
}
