// Network haptic device: a small UDP protocol on loopback (pose in, force out) for external hardware drivers.
#pragma once

#include <cstdint>
#include <string>

#include "host/haptics/haptic_device.h"

namespace inc {

// Protocol (all little-endian, one datagram per message; docs/haptics.md):
//   pose  (driver -> Incision), 80 bytes: u32 magic 0x50434E49 ("INCP"), u16 version = 1, u16 device,
//         u32 sequence, u32 buttons, f64 t_s, f64 x_m, y_m, z_m, f64 qw, qx, qy, qz
//   force (Incision -> driver, sent to the address of the newest pose), 40 bytes: u32 magic 0x46434E49
//         ("INCF"), u16 version = 1, u16 device, u32 sequence (of the pose it answers), u32 0,
//         f64 fx_n, fy_n, fz_n
// read() drains the socket without blocking and keeps the newest pose (highest sequence); malformed or
// stale datagrams are counted and dropped. Until a first pose arrives the device reports the origin.
struct UdpPose {
  std::uint16_t device = 0;
  std::uint32_t sequence = 0;
  DeviceSample sample;
};
constexpr std::size_t kUdpPoseBytes = 80, kUdpForceBytes = 40;
void encodeUdpPose(const UdpPose& pose, unsigned char out[kUdpPoseBytes]);
bool decodeUdpPose(const unsigned char* data, std::size_t size, UdpPose& pose);  // false: malformed
void encodeUdpForce(std::uint16_t device, std::uint32_t sequence, const Vec3d& force_n,
                    unsigned char out[kUdpForceBytes]);
bool decodeUdpForce(const unsigned char* data, std::size_t size, std::uint16_t& device, std::uint32_t& sequence,
                    Vec3d& force_n);

class UdpDevice : public HapticDevice {
 public:
  // Binds 127.0.0.1:port (0: any free port, see port()). Throws InputError when it cannot bind.
  UdpDevice(std::uint16_t port, std::uint16_t device_id, double max_force_n);
  ~UdpDevice() override;
  UdpDevice(const UdpDevice&) = delete;
  UdpDevice& operator=(const UdpDevice&) = delete;
  DeviceSample read(std::uint64_t tick, double t_s) override;
  void writeForce(const Vec3d& force_n) override;
  double maxForce_n() const override { return max_force_n_; }
  std::string name() const override { return "udp"; }
  std::uint16_t port() const { return port_; }
  std::uint64_t dropped() const { return dropped_; }
  bool connected() const { return have_peer_; }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0, device_id_;
  double max_force_n_;
  UdpPose latest_;
  bool have_peer_ = false;
  unsigned char peer_[128] = {};  // sockaddr_storage bytes of the newest pose's sender
  unsigned peer_len_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace inc
