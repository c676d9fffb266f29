// The scene's sensors (<implicit_sim><sensor>, step/sensors.h) against closed forms: a ball resting on the ground feels
// its weight through its contact sensor (and the ground the opposite), an IMU reads 0 in free fall, +g upwards at rest
// and the centripetal acceleration on a spinning body; bad declarations are refused naming the sensor.
#include <cmath>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/sensors.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

// A 1 kg ball of radius 0.05 m on the ground plane z = 0 (its centre at z0), with `sensors` in <implicit_sim>.
std::string BallOnGround(double z0, const std::string& sensors) {
  return "<robot name='ball_on_ground'><implicit_sim>" + sensors +
         "</implicit_sim><link name='world'/>"
         "<link name='ground'><collision><geometry><box size='1 1 0.01'/></geometry><implicit type='halfspace'/>"
         "</collision></link><joint name='ground_joint' type='fixed'><parent link='world'/><child link='ground'/>"
         "</joint><link name='ball'><inertial><mass value='1'/><inertia ixx='0.001' iyy='0.001' izz='0.001' ixy='0' "
         "ixz='0' iyz='0'/></inertial><collision><geometry><sphere radius='0.05'/></geometry></collision></link>"
         "<link name='imu_link'/><joint name='imu_joint' type='fixed'><parent link='ball'/><child link='imu_link'/>"
         "<origin xyz='0.1 0 0' rpy='0.3 -0.2 1.1'/></joint>"
         "<joint name='ball_joint' type='floating'><parent link='world'/><child link='ball'/><origin xyz='0 0 " +
         std::to_string(z0) + "'/></joint></robot>";
}

const Sensor& SensorNamed(const Model& model, const std::string& name) {
  for (const Sensor& sensor : model.sensors) {
    if (sensor.name == name) return sensor;
  }
  throw std::invalid_argument("no sensor " + name);
}

TEST(Sensors, AContactSensorFeelsTheWeightOfABallAtRestAndTheGroundTheOpposite) {
  const Model model = LoadSceneFromString(
      BallOnGround(0.05, "<sensor name='ball_bumper' type='contact' link='ball' rate='100'/>"
                         "<sensor name='ground_bumper' type='contact' link='ground'/>"),
      "ball_on_ground");
  ASSERT_EQ(model.sensors.size(), 2u);
  EXPECT_EQ(SensorNamed(model, "ball_bumper").rate_hz, 100.0);
  EXPECT_EQ(SensorNamed(model, "ground_bumper").rate_hz, 50.0);  // the default
  Data data(model);
  State state = State::Initial(model);
  StepperOptions options;  // the defaults: RATTLE
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged);
  ContactSensorReading ball, ground;
  ReadContactSensor(model, state, SensorNamed(model, "ball_bumper"), data.contacts, options.contact_threshold, &ball);
  ReadContactSensor(model, state, SensorNamed(model, "ground_bumper"), data.contacts, options.contact_threshold,
                    &ground);
  ASSERT_EQ(ball.contacts.size(), 1u);
  EXPECT_EQ(ground.contacts, ball.contacts);
  EXPECT_LT((ball.force_W - Vec3(0, 0, 9.81)).norm(), 1e-9) << ball.force_W.transpose();
  EXPECT_LT((ground.force_W + ball.force_W).norm(), 1e-12);
  EXPECT_LT(ball.moment_W.norm(), 1e-9) << ball.moment_W.transpose();  // through the centre: no moment
  // The ground's frame is at the origin, 0.05 m below the ball's centre, straight under it: no moment either.
  EXPECT_LT(ground.moment_W.norm(), 1e-9) << ground.moment_W.transpose();
}

TEST(Sensors, AnImuReadsZeroInFreeFallAndGravityUpwardsAtRest) {
  const std::string imu = "<sensor name='imu' type='imu' link='ball'/>";
  for (double z0 : {1.0, 0.05}) {  // falling (no contact within 0.1 s), resting
    SCOPED_TRACE(z0);
    const Model model = LoadSceneFromString(BallOnGround(z0, imu), "ball_on_ground");
    Data data(model);
    State state = State::Initial(model), before = state;
    StepperOptions options;
    for (int i = 0; i < 10; ++i) {
      before = state;
      ASSERT_TRUE(Step(model, options, &state, &data).converged);
    }
    const ImuReading reading = ReadImu(model, model.sensors[0], before, state, options.h);
    const Vec3 expected = z0 > 0.5 ? Vec3::Zero() : Vec3(0, 0, 9.81);
    EXPECT_LT((reading.a_S - expected).norm(), 1e-9) << reading.a_S.transpose();
    EXPECT_LT(reading.w_S.norm(), 1e-12);
    EXPECT_LT(reading.q_WS.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  }
}

TEST(Sensors, AnImuOnAFrameLinkOfASpinningBodyReadsTheCentripetalAcceleration) {
  // Without gravity the ball spins at 2 rad/s about z through its centre; the IMU frame link sits 0.1 m out along x,
  // turned by rpy (0.3, -0.2, 1.1): it reads the angular velocity and -w^2 r towards the axis in its own frame.
  const std::string urdf = BallOnGround(1.0, "<sensor name='imu' type='imu' link='imu_link' rate='1000'/>");
  std::string spinning = urdf;
  spinning.replace(spinning.find("<implicit_sim>"), 14,
                   "<implicit_sim gravity='0 0 0'><body link='ball' angular_velocity='0 0 2'/>");
  const Model model = LoadSceneFromString(spinning, "spinning");
  ASSERT_EQ(model.sensors[0].body, model.FindBody("ball"));
  Data data(model);
  State state = State::Initial(model), before = state;
  StepperOptions options;
  options.h = 1e-3;
  for (int i = 0; i < 100; ++i) {
    before = state;
    ASSERT_TRUE(Step(model, options, &state, &data).converged);
  }
  const ImuReading reading = ReadImu(model, model.sensors[0], before, state, options.h);
  const Pose X_WS = state.X_WL(model, model.FindBody("ball")) * model.sensors[0].X_LS;
  const Vec3 p_axis_to_S = Vec3(X_WS.translation().x(), X_WS.translation().y(), 0.0);
  EXPECT_NEAR(p_axis_to_S.norm(), 0.1, 1e-9);
  const Vec3 a_W = -4.0 * p_axis_to_S;  // -w^2 r
  EXPECT_LT((X_WS.linear() * reading.a_S - a_W).norm(), 2e-3 * a_W.norm()) << reading.a_S.transpose();
  EXPECT_LT((X_WS.linear() * reading.w_S - Vec3(0, 0, 2)).norm(), 1e-12);
  EXPECT_LT(reading.q_WS.angularDistance(Eigen::Quaterniond(X_WS.linear())), 1e-12);
}

TEST(Sensors, BadDeclarationsAreRefusedNamingTheSensorAndSpawnPrefixesThem) {
  const std::pair<const char*, const char*> cases[] = {
      {"<sensor name='s' type='sonar' link='ball'/>", "attribute 'type' = 'sonar' must be contact, imu or force_torque"},
      {"<sensor type='imu' link='ball'/>", "attribute 'name' must be a non-empty name"},
      {"<sensor name='s' type='imu' link='hand'/>", "<implicit_sim><sensor name='s'>: attribute 'link' must name"},
      {"<sensor name='s' type='contact' link='imu_link'/>", "must name a link of the scene with a body"},
      {"<sensor name='s' type='imu' link='ball'/><sensor name='s' type='contact' link='ball'/>", "a second sensor"},
      {"<sensor name='s' type='imu' link='ball' rate='0'/>", "attribute 'rate' = 0 is out of range (0, 1000]"},
      {"<sensor name='s' type='imu' link='ball' range='3'/>", "range"}};
  for (const auto& [sensors, expected] : cases) {
    try {
      LoadSceneFromString(BallOnGround(0.05, sensors), "ball_on_ground");
      ADD_FAILURE() << "accepted " << sensors;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
  // A spawned copy's sensors are renamed with the prefix and follow its links; deleting the links drops them.
  const std::string scene = BallOnGround(0.05, "<sensor name='imu' type='imu' link='imu_link'/>");
  SceneAddition addition;
  addition.urdf = scene;
  addition.prefix = "b_";
  addition.X_WO.translation() = Vec3(1, 0, 0);
  std::vector<std::string> added;
  const std::string both = AddToScene(scene, addition, &added);
  const Model model = LoadSceneFromString(both, "both");
  ASSERT_EQ(model.sensors.size(), 2u);
  EXPECT_EQ(model.sensors[1].name, "b_imu");
  EXPECT_EQ(model.sensors[1].link, "b_imu_link");
  EXPECT_EQ(model.sensors[1].body, model.FindBody("b_ball"));
  std::vector<std::string> removed;
  const Model one = LoadSceneFromString(RemoveFromScene(both, {"b_ball"}, &removed), "one");
  ASSERT_EQ(one.sensors.size(), 1u);
  EXPECT_EQ(one.sensors[0].name, "imu");
}

}  // namespace
}  // namespace implicit_sim
