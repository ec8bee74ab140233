#include "analysis/renderer_spec.h"

#include <gtest/gtest.h>

#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::analysis {
namespace {

std::string ErrorOf(std::string_view list) {
  try {
    ParseRendererList(list);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(RendererSpecTest, NamesMapToTheirRenderers) {
  EXPECT_EQ(ParseRendererSpec("penalty").renderer, RendererKind::kPenalty);
  EXPECT_EQ(ParseRendererSpec("impulse").renderer, RendererKind::kImpulse);
  EXPECT_EQ(ParseRendererSpec("train").renderer, RendererKind::kTrain);
  // plain renderers keep the flags' / config's parameters
  EXPECT_FALSE(ParseRendererSpec("train").render.has_value());
  // the method's walls fix e, t_c and f
  const RendererSpec w1 = ParseRendererSpec("wall1");
  ASSERT_TRUE(w1.render.has_value());
  EXPECT_EQ(w1.renderer, RendererKind::kTrain);
  EXPECT_EQ(w1.render->frequency_hz, 250.0);
  EXPECT_EQ(ParseRendererSpec("wall2").render->frequency_hz, 50.0);
  EXPECT_EQ(ParseRendererSpec("wall0").renderer, RendererKind::kImpulse);
  EXPECT_EQ(w1.name, "wall1");
  EXPECT_EQ(w1.label, "wall 1: train 250 Hz");
}

TEST(RendererSpecTest, TheWallsSetIsPenaltyAndTheThreeWalls) {
  const std::vector<RendererSpec> walls = ParseRendererList(kWallsSet);
  ASSERT_EQ(walls.size(), 4u);
  EXPECT_EQ(walls[0].name, "penalty");
  EXPECT_EQ(walls[3].name, "wall2");
}

TEST(RendererSpecTest, BadListsAreRefusedWithTheReason) {
  EXPECT_NE(ErrorOf("penalty,springy").find("unknown renderer 'springy'"), std::string::npos);
  EXPECT_NE(ErrorOf("penalty,springy").find("penalty, impulse, train"), std::string::npos);
  EXPECT_NE(ErrorOf("train:balsa").find("unknown material 'balsa'"), std::string::npos);
  EXPECT_NE(ErrorOf("penalty:wood").find("a material goes with event or train"), std::string::npos);
  EXPECT_NE(ErrorOf("wall3").find("unknown renderer"), std::string::npos);
  EXPECT_NE(ErrorOf("").find("empty"), std::string::npos);
  EXPECT_NE(ErrorOf("penalty,,train").find("empty entry"), std::string::npos);
  EXPECT_NE(ErrorOf("train,train").find("given twice"), std::string::npos);
  EXPECT_EQ(ErrorOf("penalty,impulse,train,wall0,wall1,wall2"), "");
  EXPECT_EQ(ErrorOf("event:wood,train:wood,event:rubber"), "");
}

TEST(RendererSpecTest, AMaterialSetsTheEventTransientOrTheMaterialTrain) {
  const RendererSpec event = ParseRendererSpec("event:wood");
  EXPECT_EQ(event.renderer, RendererKind::kEvent);
  ASSERT_TRUE(event.material.has_value());
  EXPECT_EQ(event.material->name, "wood");
  EXPECT_EQ(event.name, "event:wood");
  const RendererSpec train = ParseRendererSpec("train:aluminium");
  EXPECT_EQ(train.renderer, RendererKind::kTrain);
  ASSERT_TRUE(train.material.has_value());
  EXPECT_EQ(train.material->name, "aluminium");
  EXPECT_FALSE(ParseRendererSpec("train").material.has_value());
}

}  // namespace
}  // namespace rigidtouch::analysis
