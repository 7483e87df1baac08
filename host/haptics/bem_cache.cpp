// BEM cache file: a header naming what it was built for, the contact table and the inverse, each with a checksum.
#include "host/haptics/bem_cache.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "base/format_number.h"
#include "model/input_error.h"

namespace inc {

namespace {

// The magic names the format and the assembly's quadrature: a change of either makes older caches stale.
constexpr char kMagic[8] = {'I', 'N', 'C', 'B', 'E', 'M', 'C', '2'};

struct Header {
  char magic[8];
  std::uint64_t mesh_hash, supports_hash, elements;
  double youngs_modulus_pa, poisson_ratio, local_radius_m, local_spacing_m;
  std::uint64_t table_bytes, table_hash, inverse_bytes, inverse_hash;
};

// FNV-1a over 64-bit words (and the tail bytes): each step is a bijection of the running hash for a fixed word and
// of the word for a fixed hash, so changing any one word changes the result.
std::uint64_t hashBytes(const void* data, std::size_t n, std::uint64_t h = 1469598103934665603ull) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = (h ^ w) * 1099511628211ull;
  }
  for (; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

std::uint64_t hashMatrix(const Eigen::MatrixXd& m, std::uint64_t h = 1469598103934665603ull) {
  return hashBytes(m.data(), sizeof(double) * std::size_t(m.size()), h);
}

std::uint64_t tableHash(const OrganContactTable& t) { return hashMatrix(t.surface, hashMatrix(t.stiffness)); }

std::uint64_t tableBytes(std::uint64_t E) { return 8 * (9 * E + 9 * E * E); }
std::uint64_t inverseBytes(std::uint64_t E) { return 8 * 9 * E * E; }

bool readMatrix(std::FILE* f, Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols) {
  m.resize(rows, cols);
  return std::fread(m.data(), sizeof(double), std::size_t(m.size()), f) == std::size_t(m.size());
}

std::string num(double v) { return formatNumber(v); }

}  // namespace

BemCacheKey bemCacheKey(const TriangleMesh& mesh, const std::vector<BemBc>& supports, const Material& material,
                        double local_radius_m, double local_spacing_m) {
  BemCacheKey k;
  k.mesh_hash = hashBytes(mesh.vertices.data(), mesh.vertices.size() * sizeof(Vec3d));
  k.mesh_hash = hashBytes(mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]), k.mesh_hash);
  k.supports_hash = hashBytes(supports.data(), supports.size() * sizeof(BemBc));
  k.elements = mesh.triangles.size();
  k.youngs_modulus_pa = material.youngs_modulus_pa;
  k.poisson_ratio = material.poisson_ratio;
  k.local_radius_m = local_radius_m;
  k.local_spacing_m = local_spacing_m;
  return k;
}

BemCacheRead readBemCache(const std::string& path, const BemCacheKey& key, OrganContactTable& table,
                          Eigen::MatrixXd& a_inv) {
  BemCacheRead out;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    out.note = "no cache yet";
    return out;
  }
  struct Closer {
    std::FILE* f;
    ~Closer() { std::fclose(f); }
  } closer{f};
  Header h;
  if (std::fread(&h, sizeof h, 1, f) != 1) {
    out.note = "the cache file is truncated (no header)";
    return out;
  }
  if (std::memcmp(h.magic, kMagic, 8) != 0) {
    out.note = "the cache file is not a BEM cache of this version";
    return out;
  }
  const std::uint64_t E = key.elements;
  if (h.elements != E || h.mesh_hash != key.mesh_hash) {
    out.note = "the cache was built for another organ mesh";
    return out;
  }
  if (h.youngs_modulus_pa != key.youngs_modulus_pa || h.poisson_ratio != key.poisson_ratio) {
    out.note = "the cache was built for E = " + num(h.youngs_modulus_pa) + " Pa, nu = " + num(h.poisson_ratio) +
               " (now " + num(key.youngs_modulus_pa) + " Pa, " + num(key.poisson_ratio) + ")";
    return out;
  }
  if (h.supports_hash != key.supports_hash) {
    out.note = "the cache was built for other supports (fixed regions)";
    return out;
  }
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || h.table_bytes != tableBytes(E) || h.inverse_bytes != inverseBytes(E) ||
      size != sizeof(Header) + tableBytes(E) + inverseBytes(E)) {
    out.note = "the cache file is truncated or corrupt (its size does not match its header)";
    return out;
  }
  const Eigen::Index n = Eigen::Index(3 * E);
  if (h.local_radius_m == key.local_radius_m && h.local_spacing_m == key.local_spacing_m) {
    OrganContactTable t;
    if (readMatrix(f, t.stiffness, 9, Eigen::Index(E)) && readMatrix(f, t.surface, n, n) &&
        tableHash(t) == h.table_hash && t.stiffness.allFinite() && t.surface.allFinite()) {
      table = std::move(t);
      out.table = true;
      return out;
    }
    out.note = "the cache's contact table is corrupt (checksum mismatch)";
  } else {
    out.note = "the cache was built for another local model (local_radius_m " + num(h.local_radius_m) +
               ", local_spacing_m " + num(h.local_spacing_m) + ")";
  }
  Eigen::MatrixXd inv;
  if (std::fseek(f, long(sizeof(Header) + tableBytes(E)), SEEK_SET) == 0 && readMatrix(f, inv, n, n) &&
      hashMatrix(inv) == h.inverse_hash && inv.allFinite()) {
    a_inv = std::move(inv);
    out.inverse = true;
  } else {
    out.note += "; its inverse is corrupt (checksum mismatch)";
  }
  return out;
}

void writeBemCache(const std::string& path, const BemCacheKey& key, const OrganContactTable& table,
                   const Eigen::MatrixXd& a_inv) {
  const std::uint64_t E = key.elements;
  const Eigen::Index n = Eigen::Index(3 * E);
  if (table.stiffness.rows() != 9 || table.stiffness.cols() != Eigen::Index(E) || table.surface.rows() != n ||
      table.surface.cols() != n || a_inv.rows() != n || a_inv.cols() != n)
    throw InputError(path, "", "the BEM cache's matrices do not match its element count");
  Header h;
  std::memcpy(h.magic, kMagic, 8);
  h.mesh_hash = key.mesh_hash;
  h.supports_hash = key.supports_hash;
  h.elements = E;
  h.youngs_modulus_pa = key.youngs_modulus_pa;
  h.poisson_ratio = key.poisson_ratio;
  h.local_radius_m = key.local_radius_m;
  h.local_spacing_m = key.local_spacing_m;
  h.table_bytes = tableBytes(E);
  h.table_hash = tableHash(table);
  h.inverse_bytes = inverseBytes(E);
  h.inverse_hash = hashMatrix(a_inv);
  std::ostringstream tmp_name;
  tmp_name << path << ".tmp." << ::getpid();
  const std::string tmp = tmp_name.str();
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError(path, "", std::string("cannot write the BEM cache: ") + std::strerror(errno));
  auto write = [f](const void* p, std::size_t bytes) { return std::fwrite(p, 1, bytes, f) == bytes; };
  bool ok = write(&h, sizeof h) && write(table.stiffness.data(), 8 * std::size_t(table.stiffness.size())) &&
            write(table.surface.data(), 8 * std::size_t(table.surface.size())) &&
            write(a_inv.data(), 8 * std::size_t(a_inv.size()));
  ok = std::fclose(f) == 0 && ok;
  std::error_code ec;
  if (ok) std::filesystem::rename(tmp, path, ec);
  if (!ok || ec) {
    std::filesystem::remove(tmp, ec);
    throw InputError(path, "", "writing the BEM cache failed (disk full or no permission?)");
  }
}

}  // namespace inc
