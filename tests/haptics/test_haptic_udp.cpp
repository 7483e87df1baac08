// Tests of the UDP haptic device: packet round trip, newest-pose selection, force reply, malformed input.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "host/haptics/udp_device.h"

namespace inc {
namespace {

TEST(HapticUdp, PacketsRoundTripBitExactly) {
  UdpPose p;
  p.device = 3;
  p.sequence = 77;
  p.sample.t_s = 1.25;
  p.sample.position_m = {0.1, -0.2, 1.0 / 3.0};
  p.sample.buttons = 5;
  unsigned char buf[kUdpPoseBytes];
  encodeUdpPose(p, buf);
  UdpPose q;
  ASSERT_TRUE(decodeUdpPose(buf, sizeof(buf), q));
  EXPECT_EQ(q.sequence, 77u);
  EXPECT_EQ(q.sample.position_m.z, 1.0 / 3.0);
  EXPECT_EQ(q.sample.buttons, 5u);
  buf[0] ^= 1;  // bad magic
  EXPECT_FALSE(decodeUdpPose(buf, sizeof(buf), q));
  EXPECT_FALSE(decodeUdpPose(buf, sizeof(buf) - 1, q));
}

TEST(HapticUdp, LoopbackPoseInForceOut) {
  UdpDevice dev(0, 1, 3.0);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(dev.port());
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  auto send = [&](std::uint32_t seq, double x) {
    UdpPose p;
    p.device = 1;
    p.sequence = seq;
    p.sample.position_m = {x, 0.0, 0.0};
    unsigned char buf[kUdpPoseBytes];
    encodeUdpPose(p, buf);
    ::sendto(fd, buf, sizeof(buf), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to));
  };
  send(1, 0.01);
  send(3, 0.03);
  send(2, 0.02);  // late (older) datagram: dropped
  const char junk[5] = "junk";
  ::sendto(fd, junk, 4, 0, reinterpret_cast<sockaddr*>(&to), sizeof(to));
  DeviceSample s;
  for (int i = 0; i < 100 && s.position_m.x != 0.03; ++i) {  // loopback delivery is fast but asynchronous
    s = dev.read(0, 0.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  s = dev.read(0, 0.0);
  EXPECT_EQ(s.position_m.x, 0.03);
  EXPECT_EQ(dev.dropped(), 2u);
  dev.writeForce(Vec3d{0.5, -1.0, 2.0});
  unsigned char buf[64];
  timeval tv{1, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
  std::uint16_t device = 0;
  std::uint32_t seq = 0;
  Vec3d f;
  ASSERT_TRUE(decodeUdpForce(buf, std::size_t(n > 0 ? n : 0), device, seq, f));
  EXPECT_EQ(device, 1);
  EXPECT_EQ(seq, 3u);
  EXPECT_EQ(f.y, -1.0);
  ::close(fd);
}

}  // namespace
}  // namespace inc
