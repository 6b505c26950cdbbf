#include "represent/model/method.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace photomat {
namespace {

TEST(MethodTest, NamesRoundTrip) {
  for (const Method& method : AllMethods()) EXPECT_EQ(Method::Parse(method.Name()), method);
  EXPECT_EQ(Method::Parse("eigen12").eigen_k, 12);
  EXPECT_EQ(Method::Parse("eigen12").MinimumImages(), 12);
  for (const char* name : {"hsh4", "hsh9", "hsh16"}) {
    EXPECT_EQ(Method::Parse(name).Name(), name);
    EXPECT_EQ(Method::Parse(name).kind, Method::Kind::kHsh);
  }
  EXPECT_EQ(Method::Parse("hsh16").MinimumImages(), 16);
  EXPECT_THROW(Method::Parse("hsh"), Error);
  EXPECT_EQ(Method::Parse("pbr").kind, Method::Kind::kPbr);
  EXPECT_EQ(Method::Parse("pbr").Name(), "pbr");
  EXPECT_EQ(Method::Parse("rbf").kind, Method::Kind::kRbf);
  EXPECT_EQ(Method::Parse("bilinear").Name(), "bilinear");
  // The light-profile options are not part of the name, and default to unset / the defaults.
  const Method rbf = Method::Parse("rbf");
  EXPECT_FALSE(rbf.profile.rbf_width_degrees);
  EXPECT_EQ(rbf.profile.planes, LightProfileOptions::kDefaultPlanes);
}

TEST(MethodTest, AllIsTheThesisFiveAndLrgb) {
  std::vector<std::string> names;
  for (const Method& m : ParseMethodList("all")) names.push_back(m.Name());
  EXPECT_EQ(names,
            (std::vector<std::string>{"3i", "gradient", "ptm", "ptm-lrgb", "eigen3", "eigen6"}));
  EXPECT_EQ(ParseMethodList("ptm,eigen4").size(), 2u);
}

TEST(MethodTest, UnknownNamesListTheValidOnes) {
  EXPECT_THAT([] { Method::Parse("hsh5"); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("expected 3i, gradient")));
  EXPECT_THROW(Method::Parse("eigen0"), Error);
  EXPECT_THROW(Method::Parse("eigenx"), Error);
  EXPECT_THROW(ParseMethodList(","), Error);
}

}  // namespace
}  // namespace photomat
