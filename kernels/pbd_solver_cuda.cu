// The CUDA PBD/XPBD backend's model upload, state and factory; its other parts are listed in
// kernels/pbd_backend_cuda.cuh.
#include "kernels/pbd_solver_cuda.h"

#include <cstddef>
#include <string>
#include <vector>

#include "kernels/pbd_backend_cuda.cuh"

namespace inc::cuda {

// A blocking stream: it orders itself after the synchronous cudaMemcpy uploads of DeviceBuffer (legacy
// default stream), so a frame never reads an input whose DMA is still in flight.
template <typename T>
PbdCudaBackend<T>::PbdCudaBackend() {
  INC_CUDA(cudaStreamCreate(&stream_));
  live_.resize(1 + kMaxLiveBlocks);  // one allocation for the backend's life: captured frames hold its address
}

template <typename T>
PbdCudaBackend<T>::~PbdCudaBackend() {
  destroyGraph();
  for (cudaEvent_t e : events_) cudaEventDestroy(e);
  if (stream_) cudaStreamDestroy(stream_);
}

// A new model reuses the device buffers of the last one wherever they are large enough (a cut rebuilds the
// model every frame the blade enters new spheres: freeing and allocating ~100 buffers cost ~2 ms there), its
// arrays travel packed in one page-locked buffer (BulkUpload: one wait instead of ~80 synchronous copies), and
// keeps the executable graph for cudaGraphExecUpdate: the topology version makes the key stale, so the graph
// is re-captured before it is launched again.
template <typename T>
void PbdCudaBackend<T>::setModel(const PbdModel<T>& m) {
  if (m.blocks.size() > std::size_t(kMaxLiveBlocks))
    throw InputError("pbd model", "blocks", "at most " + std::to_string(kMaxLiveBlocks) + " constraint blocks on CUDA");
  ++topo_version_;
  live_dirty_ = true;
  has_coloring_ = pbdModelHasColoring(m);
  patched_ = false;
  frame_count_ = 0;
  n_ = int(m.size());
  host_rest_radii_ = m.rest_radii;
  rotation_block_ = m.rotation_block;
  bulk_.add(rest_positions_, m.rest_positions);
  bulk_.add(x_, m.rest_positions);
  bulk_.zero(v_, m.size());
  bulk_.zero(x_prev_, m.size());
  bulk_.add(masses_, m.masses);
  bulk_.add(inv_mass_, m.inv_mass);
  bulk_.add(w_, m.inv_mass);
  bulk_.add(rest_radii_, m.rest_radii);
  bulk_.add(radii_, m.rest_radii);
  bulk_.add(radii_next_, m.rest_radii);
  has_inset_ = !m.contact_inset.empty();
  if (has_inset_) bulk_.add(inset_, m.contact_inset);
  std::vector<pbd::Quat<T>> ident(m.size());
  bulk_.add(rotations_, ident);
  bulk_.zero(active_, m.size());
  bulk_.add(planes_, m.planes);
  bulk_.add(boxes_, m.boxes);
  n_planes_ = int(m.planes.size());
  n_boxes_ = int(m.boxes.size());
  bulk_.add(ov_off_, m.overlap_offsets);
  bulk_.add(ov_ids_, m.overlap_ids);
  bulk_.add(rest_cell_, m.rest_cell_volume);
  bulk_.add(samples_, m.ball_samples);
  have_volume_data_ =
      m.rest_cell_volume.size() == m.size() && !m.ball_samples.empty() && m.overlap_offsets.size() == m.size() + 1;
  updateStaging();
  blocks_.resize(m.blocks.size());
  for (std::size_t bi = 0; bi < m.blocks.size(); ++bi) {
    const PbdConstraintBlock<T>& s = m.blocks[bi];
    DeviceBlock<T>& d = blocks_[bi];
    d.kind = s.kind;
    d.solve = s.solve;
    d.stiffness = s.stiffness;
    d.count = int(s.count());
    bulk_.add(d.offsets, s.offsets);
    bulk_.add(d.ids, s.ids);
    bulk_.add(d.particle_offsets, s.particle_offsets);
    bulk_.add(d.particle_slots, s.particle_slots);
    bulk_.add(d.order, s.coloring.order);
    d.color_offsets = s.coloring.color_offsets;
    bulk_.add(d.color_offsets_dev, s.coloring.color_offsets);
    bulk_.add(d.rest, s.rest);
    bulk_.add(d.compliance, s.compliance);
    bulk_.add(d.jacobi_scale, s.jacobi_scale);
    bulk_.add(d.rest_vec, s.rest_vec);
    bulk_.zero(d.lambda, s.multiplierCount());
    bulk_.zero(d.slot_corr, s.slotCount());
  }
  // Host copies for the cluster frame's plan, kept only for models whose particle replica can fit a CTA's shared
  // memory (the plan needs them; a large model, e.g. a tearing sheet re-set every tearing frame, skips the copy).
  cluster_meta_.clear();
  if (clusterStageBytes<T>(n_, 0) <= std::size_t(sharedOptin()))
    for (const PbdConstraintBlock<T>& b : m.blocks)
      cluster_meta_.push_back({b.offsets, b.particle_slots, b.solve, int(b.kind)});
  cluster_planned_for_ = -1;  // planned at the first Jacobi frame (planCluster)
  int reduced_blocks = 0;
  for (const DeviceBlock<T>& d : blocks_)
    if (d.kind == PbdConstraintKind::Distance && d.solve && d.count > 0) ++reduced_blocks;
  bulk_.zero(partials_, std::size_t(2 * reduced_blocks + 3) * (kReduceBlocks + 1));  // partials, then totals
  INC_CUDA(cudaDeviceSynchronize());  // no stream (this one or another) still reads the old model's buffers
  bulk_.flush(stream_);               // one wait for every copy and memset above
}

template <typename T>
void PbdCudaBackend<T>::setState(const PbdState<T>& s) {
  const std::size_t n = std::size_t(n_);
  if (s.positions.size() != n || s.velocities.size() != n || s.radii.size() != n || s.rotations.size() != n)
    throw InputError("pbd state", "size", "state arrays must have one entry per particle");
  INC_CUDA(cudaStreamSynchronize(stream_));
  x_.upload(s.positions);
  v_.upload(s.velocities);
  radii_.upload(s.radii);
  rotations_.upload(s.rotations);
}

template <typename T>
void PbdCudaBackend<T>::getPositions(std::vector<Vec3<T>>& positions) const {
  INC_CUDA(cudaStreamSynchronize(stream_));
  positions = x_.download();
}

template <typename T>
void PbdCudaBackend<T>::getState(PbdState<T>& s) const {
  INC_CUDA(cudaStreamSynchronize(stream_));
  s.positions = x_.download();
  s.velocities = v_.download();
  s.radii = radii_.download();
  s.rotations = rotations_.download();
}

template <typename T>
MemoryReport PbdCudaBackend<T>::memory() const {
  MemoryReport r;
  std::size_t b = x_.capacityBytes() + v_.capacityBytes() + x_prev_.capacityBytes() + rest_positions_.capacityBytes() +
                  masses_.capacityBytes() + inv_mass_.capacityBytes() + w_.capacityBytes() +
                  rest_radii_.capacityBytes() + radii_.capacityBytes() + radii_next_.capacityBytes() +
                  rotations_.capacityBytes() + active_.capacityBytes() + ov_off_.capacityBytes() +
                  ov_ids_.capacityBytes() + rest_cell_.capacityBytes() + samples_.capacityBytes();
  for (const DeviceBlock<T>& d : blocks_)
    b += d.offsets.capacityBytes() + d.ids.capacityBytes() + d.particle_offsets.capacityBytes() +
         d.particle_slots.capacityBytes() + d.order.capacityBytes() + d.rest.capacityBytes() +
         d.compliance.capacityBytes() + d.jacobi_scale.capacityBytes() + d.rest_vec.capacityBytes() +
         d.lambda.capacityBytes() + d.slot_corr.capacityBytes();
  r.device_bytes = b;
  r.host_bytes = host_rest_radii_.size() * sizeof(T);
  return r;
}

// The class's members defined above, its vtable and its inline members; the other files of the backend
// (kernels/pbd_backend_cuda.cuh lists them) instantiate the members they define that are used elsewhere.
template class PbdCudaBackend<float>;
template class PbdCudaBackend<double>;

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCudaBackend() {
  return std::make_unique<PbdCudaBackend<T>>();
}

template <typename T>
PbdDevicePatch<T>* pbdDevicePatch(PbdBackend<T>& backend) {
  return dynamic_cast<PbdDevicePatch<T>*>(&backend);
}

template PbdDevicePatch<float>* pbdDevicePatch<float>(PbdBackend<float>&);
template PbdDevicePatch<double>* pbdDevicePatch<double>(PbdBackend<double>&);

template std::unique_ptr<PbdBackend<float>> makePbdCudaBackend<float>();
template std::unique_ptr<PbdBackend<double>> makePbdCudaBackend<double>();

}  // namespace inc::cuda
