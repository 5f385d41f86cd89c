// Loads a Basalt calibration JSON the way Basalt's loader reads it (cereal's JSON archive,
// the members of basalt::Calibration looked up by name in Basalt's order, each fixed-size
// vector read as a JSON array whose length must match, as basalt-headers' eigen_io.h does)
// and prints the IMU noise members with 17 significant digits. Written for the tests from
// the facts of Basalt's layout; camera members are read as plain arrays (their contents are
// not what is checked). Usage: basalt_imu_load FILE
#include <cereal/archives/json.hpp>
#include <cereal/types/vector.hpp>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

// A fixed-length vector of doubles as Basalt's text archives store one: a JSON array.
template <size_t N>
struct Fixed {
  double v[N];
  template <class Archive>
  void serialize(Archive& ar) {
    cereal::size_type s = N;
    ar(cereal::make_size_tag(s));
    if (s != N) throw std::runtime_error("matrix has incorrect length");
    for (size_t i = 0; i < N; i++) ar(v[i]);
  }
};

struct Calibration {
  std::vector<double> T_imu_cam, intrinsics, resolution, vignette;
  Fixed<9> calib_accel_bias;
  Fixed<12> calib_gyro_bias;
  double imu_update_rate = 0;
  Fixed<3> accel_noise_std, gyro_noise_std, accel_bias_std, gyro_bias_std;
  int64_t cam_time_offset_ns = 0;
  template <class Archive>
  void serialize(Archive& ar) {
    ar(cereal::make_nvp("T_imu_cam", T_imu_cam), cereal::make_nvp("intrinsics", intrinsics),
       cereal::make_nvp("resolution", resolution),
       cereal::make_nvp("calib_accel_bias", calib_accel_bias),
       cereal::make_nvp("calib_gyro_bias", calib_gyro_bias),
       cereal::make_nvp("imu_update_rate", imu_update_rate),
       cereal::make_nvp("accel_noise_std", accel_noise_std),
       cereal::make_nvp("gyro_noise_std", gyro_noise_std),
       cereal::make_nvp("accel_bias_std", accel_bias_std),
       cereal::make_nvp("gyro_bias_std", gyro_bias_std),
       cereal::make_nvp("cam_time_offset_ns", cam_time_offset_ns),
       cereal::make_nvp("vignette", vignette));
  }
};

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  std::ifstream is(argv[1]);
  Calibration c;
  try {
    cereal::JSONInputArchive ar(is);
    ar(c);  // the root's first value: "value0", as Basalt's loader reads it
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cereal: %s\n", e.what());
    return 1;
  }
  std::printf("%.17g", c.imu_update_rate);
  for (auto* f : {&c.accel_noise_std, &c.gyro_noise_std, &c.accel_bias_std, &c.gyro_bias_std})
    for (double x : f->v) std::printf(" %.17g", x);
  std::printf("\n");
  return 0;
}
