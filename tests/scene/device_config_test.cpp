// Tests of scene/device_config.{h,cpp}: device spec strings parsed into the typed
// haptics::DeviceConfig (every key into its field) and opened, with every error naming the
// spec and the problem.

#include "hof/scene/device_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <variant>

#include "support/temp_dir.h"

namespace hof {
namespace {

using hof::testing::TempDir;

std::string open_error(const std::string& spec) {
  auto d = scene::open_device(spec);
  EXPECT_FALSE(d) << spec << " opened";
  return d ? std::string{} : d.error().to_string();
}

void expect_error(const std::string& spec, const std::string& fragment, bool names_spec = true) {
  const std::string message = open_error(spec);
  EXPECT_NE(message.find(fragment), std::string::npos) << spec << " → " << message;
  if (names_spec) {
    EXPECT_NE(message.find("device spec '" + spec + "'"), std::string::npos) << message;
  }
}

TEST(DeviceSpec, OpensTheSimulatedBackends) {
  auto poke = scene::open_device("scripted:poke");
  ASSERT_TRUE(poke) << poke.error().to_string();
  EXPECT_EQ((*poke)->backend(), "scripted");
  EXPECT_TRUE((*poke)->read(0.0).valid);
  EXPECT_NEAR(((*poke)->read(0.0).position_m - Vec3(0, 0.05, 0)).norm(), 0.0, 1e-15);

  auto custom = scene::open_device(
      "scripted:poke, start=0.01;0.02;0, direction=0;0;-2, depth=0.005, speed=0.02, "
      "hold=0.5, approach=0.01, repeat=3, model=omni");
  ASSERT_TRUE(custom) << custom.error().to_string();
  EXPECT_EQ((*custom)->spec().max_force_n, 3.3);
  EXPECT_EQ((*custom)->spec().max_stiffness_n_per_m, 700.0);
  const auto& motion = dynamic_cast<haptics::ScriptedDevice&>(**custom).motion();
  EXPECT_NEAR((motion.deepest_point() - Vec3(0.01, 0.02, -0.015)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(motion.duration(), 3 * (2 * 0.015 / 0.02 + 0.5), 1e-12);

  for (const char* spec : {"scripted:press-and-slide,slide=0;0;1,distance=0.01,slide_speed=0.02",
                           "scripted:circle,centre=0;0.02;0,normal=0;0;1,radius=0.03,period=1,repeat",
                           "scripted:hold,start=0;0.1;0", "virtual-hand:poke",
                           "virtual-hand:circle,repeat=forever,mass=0.2,stiffness=300,damping=3,device_damping=1,"
                           "substep=0.0005,model=falcon",
                           "virtual-hand:hold,integrator=exact"}) {
    auto d = scene::open_device(spec);
    ASSERT_TRUE(d) << spec << ": " << d.error().to_string();
    EXPECT_TRUE((*d)->read(0.5).valid) << spec;
  }
  auto hand = scene::open_device("virtual-hand:poke,mass=0.2");
  ASSERT_TRUE(hand);
  EXPECT_EQ((*hand)->backend(), "virtual-hand");
  EXPECT_EQ(dynamic_cast<haptics::VirtualHandDevice&>(**hand).params().mass_kg, 0.2);

  auto falcon = scene::device_spec_for_model("falcon");
  ASSERT_TRUE(falcon);
  EXPECT_EQ(falcon->max_force_n, 8.0);
  EXPECT_EQ(falcon->max_stiffness_n_per_m, 3000.0);
  EXPECT_EQ(scene::device_spec_for_model("touch")->max_stiffness_n_per_m, 400.0);
}

TEST(DeviceSpec, OpensAReplayFile) {
  TempDir dir;
  const auto path = dir.write("r.csv", "t,x,y,z\n0,0,0,0\n1,0.01,0,0\n");
  auto d = scene::open_device("replay:" + path.string() + ",loop");
  ASSERT_TRUE(d) << d.error().to_string();
  EXPECT_EQ((*d)->backend(), "replay");
  EXPECT_TRUE((*d)->read(5.5).valid);
  EXPECT_NEAR((*d)->read(5.5).position_m.x(), 0.005, 1e-15);
}

TEST(DeviceSpec, ErrorsNameTheSpecAndTheProblem) {
  expect_error("joystick:1", "unknown backend 'joystick'");
  expect_error("", "empty backend");
  expect_error("scripted:poke,depht=0.01", "unknown key 'depht' for scripted poke");
  expect_error("scripted:circle,depth=0.01", "unknown key 'depth'");
  expect_error("scripted:poke,depth=abc", "bad value 'abc' for key 'depth'");
  expect_error("scripted:poke,depth", "key 'depth' needs a number");
  expect_error("scripted:poke,depth=nan", "bad value 'nan' for key 'depth'");
  expect_error("scripted:poke,start=1;2", "bad value '1;2' for key 'start' (expected three numbers x;y;z)");
  expect_error("scripted:poke,start=1;2;3;4", "bad value '1;2;3;4'");
  expect_error("scripted:poke,speed=-1", "speed must be > 0");
  expect_error("scripted:poke,repeat=two", "bad value 'two' for key 'repeat'");
  expect_error("scripted:poke,depth=1,depth=2", "key 'depth' is given twice");
  expect_error("scripted:poke,,depth=1", "empty option");
  expect_error("scripted:wiggle", "unknown motion 'wiggle'");
  expect_error("scripted", "missing motion");
  expect_error("scripted:poke,model=phantom", "unknown device model 'phantom'");
  expect_error("scripted:poke,mass=1", "unknown key 'mass'");
  expect_error("virtual-hand:poke,mass=-1", "mass must be > 0");
  expect_error("virtual-hand:poke,stiffness=x", "bad value 'x' for key 'stiffness'");
  expect_error("virtual-hand:poke,integrator=rk4", "bad value 'rk4' for key 'integrator'");
  expect_error("replay:", "missing file");
  expect_error("replay:a.csv,loop=maybe", "bad value 'maybe' for key 'loop'");
  expect_error("replay:a.csv,speed=2", "unknown key 'speed' for replay");
  expect_error("udp:", "missing port");
  expect_error("udp:http", "bad port 'http'");
  expect_error("udp:70000", "bad port '70000'");
  expect_error("udp::5000", "empty host");
  expect_error("udp:0,timeout=-1", "timeout must be > 0");
  expect_error("udp:0,rate=1000", "unknown key 'rate' for udp");
  expect_error("spacemouse:1", "spacemouse takes no argument");
  expect_error("spacemouse,scale=fast", "bad value 'fast' for key 'scale'");

  TempDir dir;
  const std::string missing = (dir.path() / "missing.csv").string();
  auto d = scene::open_device("replay:" + missing);
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().code, ErrorCode::kIo);
  EXPECT_NE(d.error().to_string().find(missing + ": replay: no such file"), std::string::npos) << d.error().to_string();
}

TEST(DeviceSpec, PalpateAndMouseSpecs) {
  // A spec string builds a palpation, and a count out of range is refused by name.
  auto device = scene::open_device("scripted:palpate,start=0;0.05;0,direction=0;-1;0,step=0.02;0;0,count=3");
  ASSERT_TRUE(device) << device.error().to_string();
  auto bad = scene::open_device("scripted:palpate,count=40");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("count=40"), std::string::npos) << bad.error().message;
  auto mouse = scene::open_device("mouse");
  ASSERT_TRUE(mouse) << mouse.error().to_string();
  EXPECT_EQ((*mouse)->backend(), "mouse");
  EXPECT_FALSE(scene::open_device("mouse:extra"));
  EXPECT_FALSE(scene::open_device("mouse,speed=2"));
}

// Round trips: every key lands in its typed field.
template <class T>
T parsed(const std::string& spec) {
  auto c = scene::parse_device_spec(spec);
  EXPECT_TRUE(c) << spec << ": " << (c ? std::string{} : c.error().to_string());
  if (!c) return T{};
  EXPECT_TRUE(std::holds_alternative<T>(*c)) << spec << " parsed as alternative " << c->index();
  return std::holds_alternative<T>(*c) ? std::get<T>(*c) : T{};
}

TEST(DeviceSpec, ParsesEveryKeyIntoItsTypedField) {
  const auto poke = parsed<haptics::ScriptedConfig>(
      "scripted:poke, start=0.01;0.02;0, direction=0;0;-2, depth=0.005, speed=0.02, hold=0.5, approach=0.01, repeat=3, "
      "force=1.5, "
      "model=omni");
  EXPECT_EQ(poke.motion.kind, haptics::MotionKind::kPoke);
  EXPECT_EQ(poke.motion.start_m, Vec3(0.01, 0.02, 0.0));
  EXPECT_EQ(poke.motion.direction, Vec3(0.0, 0.0, -2.0));
  EXPECT_EQ(poke.motion.depth_m, 0.005);
  EXPECT_EQ(poke.motion.speed_m_per_s, 0.02);
  EXPECT_EQ(poke.motion.hold_s, 0.5);
  EXPECT_EQ(poke.motion.approach_m, 0.01);
  EXPECT_EQ(poke.motion.repeat, 3U);
  EXPECT_EQ(poke.motion.stop_force_n, 1.5);
  EXPECT_EQ(poke.spec.model, "omni");
  EXPECT_EQ(poke.spec.max_force_n, 3.3);

  const auto slide = parsed<haptics::ScriptedConfig>(
      "scripted:press-and-slide,slide=0;0;1,distance=0.01,slide_speed=0.02,hold=forever");
  EXPECT_EQ(slide.motion.kind, haptics::MotionKind::kPressAndSlide);
  EXPECT_EQ(slide.motion.slide_direction, Vec3(0, 0, 1));
  EXPECT_EQ(slide.motion.slide_distance_m, 0.01);
  EXPECT_EQ(slide.motion.slide_speed_m_per_s, 0.02);
  EXPECT_TRUE(std::isinf(slide.motion.hold_s));

  const auto palpate = parsed<haptics::ScriptedConfig>("scripted:palpate,step=0.02;0;0,count=3");
  EXPECT_EQ(palpate.motion.palpation_step_m, Vec3(0.02, 0, 0));
  EXPECT_EQ(palpate.motion.palpation_count, 3U);

  const auto circle =
      parsed<haptics::ScriptedConfig>("scripted:circle,center=0;0.02;0,normal=0;0;1,radius=0.03,period=2,repeat");
  EXPECT_EQ(circle.motion.kind, haptics::MotionKind::kCircle);
  EXPECT_EQ(circle.motion.centre_m, Vec3(0, 0.02, 0));
  EXPECT_EQ(circle.motion.normal, Vec3(0, 0, 1));
  EXPECT_EQ(circle.motion.radius_m, 0.03);
  EXPECT_EQ(circle.motion.period_s, 2.0);
  EXPECT_EQ(circle.motion.repeat, 0U);  // a bare repeat: forever

  const auto hold = parsed<haptics::ScriptedConfig>("scripted:hold,start=0;0.1;0");
  EXPECT_EQ(hold.motion.kind, haptics::MotionKind::kHold);
  EXPECT_TRUE(std::isinf(hold.motion.hold_s));  // a held target stays unless told

  const auto hand = parsed<haptics::VirtualHandConfig>(
      "virtual-hand:circle,mass=0.2,stiffness=300,damping=3,device_damping=1,substep=0.0005,integrator=exact,model="
      "falcon");
  EXPECT_EQ(hand.motion.kind, haptics::MotionKind::kCircle);
  EXPECT_EQ(hand.hand.mass_kg, 0.2);
  EXPECT_EQ(hand.hand.stiffness_n_per_m, 300.0);
  EXPECT_EQ(hand.hand.damping_n_s_per_m, 3.0);
  EXPECT_EQ(hand.hand.device_damping_n_s_per_m, 1.0);
  EXPECT_EQ(hand.hand.substep_s, 0.0005);
  EXPECT_EQ(hand.hand.integrator, haptics::HandIntegrator::kExactZeroOrderHold);
  EXPECT_EQ(hand.spec.max_force_n, 8.0);
  EXPECT_EQ(parsed<haptics::VirtualHandConfig>("virtual-hand:poke,integrator=euler").hand.integrator,
            haptics::HandIntegrator::kSemiImplicitEuler);

  const auto replay = parsed<haptics::ReplayConfig>("replay:some/file.csv,loop,model=touch");
  EXPECT_EQ(replay.file, std::filesystem::path("some/file.csv"));
  EXPECT_TRUE(replay.loop);
  EXPECT_EQ(replay.spec.max_stiffness_n_per_m, 400.0);
  EXPECT_FALSE(parsed<haptics::ReplayConfig>("replay:f.csv,loop=no").loop);

  const auto udp = parsed<haptics::UdpDeviceConfig>("udp:192.0.2.1:5005,timeout=0.2,hello_wait=1.5");
  EXPECT_EQ(udp.host, "192.0.2.1");
  EXPECT_EQ(udp.port, 5005);
  EXPECT_EQ(udp.timeout_s, 0.2);
  EXPECT_EQ(udp.hello_wait_s, 1.5);
  EXPECT_FALSE(udp.key);
  EXPECT_EQ(parsed<haptics::UdpDeviceConfig>("udp:7000").host, "");

  EXPECT_EQ(parsed<haptics::SpacemouseConfig>("spacemouse,scale=0.0001").scale_m_per_unit_s, 0.0001);
  EXPECT_EQ(parsed<haptics::MouseConfig>("mouse,model=omni").spec.max_force_n, 3.3);
  // The mouse keeps its name under the virtual device's figures.
  EXPECT_EQ(parsed<haptics::MouseConfig>("mouse").spec.model, "mouse");
  EXPECT_EQ(parsed<haptics::MouseConfig>("mouse,model=virtual").spec.model, "mouse");
  EXPECT_EQ(parsed<haptics::MouseConfig>("mouse,model=virtual").spec.max_force_n, haptics::DeviceSpec{}.max_force_n);
  EXPECT_EQ(parsed<haptics::ReplayConfig>("replay:a.csv,model=virtual").spec.model, "virtual");

  const auto dhd = parsed<haptics::DhdConfig>("dhd,index=2,library=/opt/libdhd.so,model=falcon");
  EXPECT_EQ(dhd.index, 2);
  EXPECT_EQ(dhd.library, "/opt/libdhd.so");
  ASSERT_TRUE(dhd.model);
  EXPECT_EQ(dhd.model->max_force_n, 8.0);
  EXPECT_FALSE(parsed<haptics::DhdConfig>("dhd").model);

  const auto hd =
      parsed<haptics::OpenHapticsConfig>("openhaptics,device=Default Device,library=/opt/libHD.so,model=touch");
  EXPECT_EQ(hd.device, "Default Device");
  EXPECT_EQ(hd.library, "/opt/libHD.so");
  ASSERT_TRUE(hd.model);
  EXPECT_EQ(hd.model->max_stiffness_n_per_m, 400.0);
}

TEST(DeviceSpec, ParseErrorsOfTheOtherBackends) {
  expect_error("scripted:poke,=1", "option '=1' has no key");
  expect_error("scripted:poke,", "empty option");
  expect_error("scripted:palpate,count=0", "count=0: a whole number of presses from 1 to");
  expect_error("scripted:palpate,count=2.5", "count=2.5");
  expect_error("replay:a.csv,model=phantom", "unknown device model 'phantom'");
  expect_error("udp:0,key=", "key needs a file");
  expect_error("udp:192.0.2.10:0", "key=FILE");  // a remote bridge authenticates: its key from a file
  expect_error("udp:0,timeout", "key 'timeout' needs a number");
  expect_error("mouse:extra", "mouse takes no argument");
  expect_error("mouse,speed=2", "unknown key 'speed' for mouse (known: model)");
  expect_error("dhd:1", "dhd takes no argument");
  expect_error("dhd,index=-1", "index=-1: a device number from 0");
  expect_error("dhd,index=1.5", "index=1.5");
  expect_error("dhd,model=phantom", "unknown device model 'phantom'");
  expect_error("dhd,port=1", "unknown key 'port' for dhd");
  expect_error("openhaptics:x", "openhaptics takes no argument");
  expect_error("openhaptics,model=phantom", "unknown device model 'phantom'");
  expect_error("openhaptics,index=1", "unknown key 'index' for openhaptics");
  // Parsing alone names the same problems, before anything is opened.
  auto parse = scene::parse_device_spec("scripted:poke,depht=0.01");
  ASSERT_FALSE(parse);
  EXPECT_EQ(parse.error().message.rfind("device spec 'scripted:poke,depht=0.01': unknown key 'depht'", 0), 0U)
      << parse.error().message;
  EXPECT_TRUE(scene::parse_device_spec("scripted:poke,speed=-1")) << "the motion is checked when opened";
}

}  // namespace
}  // namespace hof
