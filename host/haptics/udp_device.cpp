// UDP haptic device: packet encoding/decoding and the non-blocking loopback socket.
#include "host/haptics/udp_device.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "model/input_error.h"

namespace inc {

namespace {
constexpr std::uint32_t kPoseMagic = 0x50434E49u, kForceMagic = 0x46434E49u;
constexpr std::uint16_t kVersion = 1;

// Explicit little-endian byte order, independent of the host.
void putU16(unsigned char* p, std::uint16_t v) {
  p[0] = v & 0xff;
  p[1] = (v >> 8) & 0xff;
}
void putU32(unsigned char* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = (v >> (8 * i)) & 0xff;
}
void putF64(unsigned char* p, double d) {
  std::uint64_t v;
  std::memcpy(&v, &d, 8);
  for (int i = 0; i < 8; ++i) p[i] = (v >> (8 * i)) & 0xff;
}
std::uint16_t getU16(const unsigned char* p) { return std::uint16_t(p[0] | (p[1] << 8)); }
std::uint32_t getU32(const unsigned char* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= std::uint32_t(p[i]) << (8 * i);
  return v;
}
double getF64(const unsigned char* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= std::uint64_t(p[i]) << (8 * i);
  double d;
  std::memcpy(&d, &v, 8);
  return d;
}
}  // namespace

void encodeUdpPose(const UdpPose& pose, unsigned char out[kUdpPoseBytes]) {
  putU32(out, kPoseMagic);
  putU16(out + 4, kVersion);
  putU16(out + 6, pose.device);
  putU32(out + 8, pose.sequence);
  putU32(out + 12, pose.sample.buttons);
  putF64(out + 16, pose.sample.t_s);
  for (int k = 0; k < 3; ++k) putF64(out + 24 + 8 * k, pose.sample.position_m[k]);
  for (int k = 0; k < 4; ++k) putF64(out + 48 + 8 * k, pose.sample.orientation[k]);
}

bool decodeUdpPose(const unsigned char* d, std::size_t size, UdpPose& pose) {
  if (size != kUdpPoseBytes || getU32(d) != kPoseMagic || getU16(d + 4) != kVersion) return false;
  UdpPose p;
  p.device = getU16(d + 6);
  p.sequence = getU32(d + 8);
  p.sample.buttons = getU32(d + 12);
  p.sample.t_s = getF64(d + 16);
  for (int k = 0; k < 3; ++k) p.sample.position_m[k] = getF64(d + 24 + 8 * k);
  double qn = 0.0;
  for (int k = 0; k < 4; ++k) {
    p.sample.orientation[k] = getF64(d + 48 + 8 * k);
    qn += p.sample.orientation[k] * p.sample.orientation[k];
  }
  if (!isFinite(p.sample.position_m) || !std::isfinite(qn) || std::fabs(std::sqrt(qn) - 1.0) > 1e-3) return false;
  pose = p;
  return true;
}

void encodeUdpForce(std::uint16_t device, std::uint32_t sequence, const Vec3d& f, unsigned char out[kUdpForceBytes]) {
  putU32(out, kForceMagic);
  putU16(out + 4, kVersion);
  putU16(out + 6, device);
  putU32(out + 8, sequence);
  putU32(out + 12, 0);
  for (int k = 0; k < 3; ++k) putF64(out + 16 + 8 * k, f[k]);
}

bool decodeUdpForce(const unsigned char* d, std::size_t size, std::uint16_t& device, std::uint32_t& sequence,
                    Vec3d& f) {
  if (size != kUdpForceBytes || getU32(d) != kForceMagic || getU16(d + 4) != kVersion) return false;
  device = getU16(d + 6);
  sequence = getU32(d + 8);
  for (int k = 0; k < 3; ++k) f[k] = getF64(d + 16 + 8 * k);
  return true;
}

UdpDevice::UdpDevice(std::uint16_t port, std::uint16_t device_id, double max_force_n)
    : device_id_(device_id), max_force_n_(max_force_n) {
  const std::string where = "<udp device>";
  if (!(max_force_n > 0.0) || !std::isfinite(max_force_n)) throw InputError(where, "max_force_n", "must be > 0");
  fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) throw InputError(where, "socket", std::strerror(errno));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);  // loopback only: no network exposure
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    const std::string err = std::strerror(errno);
    ::close(fd_);
    throw InputError(where, "port " + std::to_string(port), "cannot bind: " + err);
  }
  socklen_t len = sizeof(addr);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  latest_.device = device_id_;
}

UdpDevice::~UdpDevice() {
  if (fd_ >= 0) ::close(fd_);
}

DeviceSample UdpDevice::read(std::uint64_t, double t_s) {
  unsigned char buf[256];
  for (;;) {
    sockaddr_storage from{};
    socklen_t len = sizeof(from);
    const ssize_t n = ::recvfrom(fd_, buf, sizeof(buf), MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from), &len);
    if (n < 0) break;  // EAGAIN: drained
    UdpPose p;
    if (!decodeUdpPose(buf, std::size_t(n), p) || p.device != device_id_ ||
        (have_peer_ && p.sequence <= latest_.sequence)) {
      ++dropped_;
      continue;
    }
    latest_ = p;
    std::memcpy(peer_, &from, std::min<std::size_t>(len, sizeof(peer_)));
    peer_len_ = len;
    have_peer_ = true;
  }
  DeviceSample s = latest_.sample;
  s.t_s = t_s;
  return s;
}

void UdpDevice::writeForce(const Vec3d& force_n) {
  if (!have_peer_) return;
  unsigned char out[kUdpForceBytes];
  encodeUdpForce(device_id_, latest_.sequence, force_n, out);
  ::sendto(fd_, out, sizeof(out), MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(peer_), socklen_t(peer_len_));
}

}  // namespace inc
