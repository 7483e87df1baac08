// The DissectionSimulation class, declared for the host/dissection_*.cpp files that define its members.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/background_task.h"
#include "host/assembly/pbd_builders.h"
#include "host/compiled/compiled_scene.h"
#include "host/cut/cut_nodal_region.h"
#include "host/cut/cut_repack.h"
#include "host/cut/cut_surface_state.h"
#include "host/cut/cut_swept_surface.h"
#include "host/io/mesh.h"
#include "host/io/triangle_bvh.h"
#include "host/sim/dissection_conversion.h"
#include "host/sim/dissection_render_layers.h"
#include "host/sim/dissection_skin.h"
#include "host/sim/dissection_stroke.h"
#include "host/sim/dissection_stroke_end.h"
#include "host/sim/dissection_surface_opening.h"
#include "host/sim/grasper.h"
#include "host/sim/interactive_tool.h"
#include "host/sim/simulation_model.h"
#include "model/backend.h"
#include "model/pbd_model.h"

namespace inc::dissection {

// PBD metaballs cut by scalpel strokes (host/sim/dissection_simulation.h says what it does). Its members live by
// concern: the frame and the SimulationModel interface (host/sim/dissection_simulation.cpp), strokes
// (host/sim/dissection_stroke.cpp), conversions (host/sim/dissection_conversion.cpp), a stroke's end
// (host/sim/dissection_stroke_end.cpp), the coupled frame (host/sim/dissection_coupled_frame.cpp), the surface
// (host/sim/dissection_surface.cpp) and the frame report (host/sim/dissection_report.cpp). Each file instantiates its
// members for float and double.
template <typename T>
class DissectionSimulation final : public SimulationModel {
 public:
  DissectionSimulation(const CompiledScene& scene, BackendKind backend);

  std::string name() const override { return "dissection"; }
  BackendKind backend() const override { return backend_->kind(); }
  std::size_t particleCount() const override { return model_.size(); }
  std::string buildNote() const override { return fill_note_; }
  FrameReport advance(double frame_dt) override;
  void saveCheckpoint() override;
  void restoreCheckpoint() override;
  void scaleTimeStep(double factor) override;
  void currentPositions(std::vector<Vec3d>& out) const override;
  bool currentSurface(TriangleMesh& out) const override;
  MemoryReport memory() const override;
  void cutWallTriangles(std::vector<std::uint8_t>& out) const override;
  void renderLayers(RenderLayers& out) const override;
  ToolSupport toolSupport() const override { return {true, true}; }
  ToolResult applyTool(const ToolEvent& e) override;

 private:
  struct Timers {
    double sweep_ms = 0, convert_ms = 0, exchange_ms = 0, repack_ms = 0, apply_ms = 0;
    double convert_pbd_ms = 0;      // of convert_ms: the PBD model rebuilt without the converted spheres
    double convert_prepare_ms = 0;  // the conversions' rest-configuration work (off the frame when delayed)
    double open_wait_ms = 0;        // of apply_ms: waiting for the surface opening's worker
    double convert_mls_ms = 0;      // of convert_ms: the MLS solver rebuilt on the points
    double convert_sample_ms = 0, convert_supports_ms = 0, convert_mls_model_ms = 0, convert_mls_setup_ms = 0;
    double convert_mls_build_ms = 0;
    double convert_pbd_build_ms = 0;               // of convert_pbd_ms: the host build (buildMetaballPbdModel)
    double convert_wait_ms = 0;                    // of convert_ms: waiting for the MLS half after the PBD half
    double apply_region_ms = 0, apply_pbd_ms = 0;  // of convert_ms, preloaded: the two state transfers in turn
    double convert_apply_ms = 0;                   // of convert_ms: a delayed conversion applied at the frame's start
    double mls_ms = 0;         // wall time of the MLS advances (launches, the GPU's work, the reductions' downloads)
    double apply_wait_ms = 0;  // of apply_ms: waiting for the stroke end's worker
  };
  // What a frame's simulation returns to its report.
  struct FrameOutcome {
    PbdFrameStats pbd;
    MlsFrameStats mls;
    bool mls_finite = true;
    int exchanges = 0, pbd_substeps = 0;
  };
  // The coupling's anchors over a coupled frame: the interface spheres (base indices), their eq. 13 targets, where
  // the PBD model had them at the last exchange, and which PBD spheres are kinematic.
  struct InterfaceAnchors {
    std::vector<std::int32_t> ids;
    std::vector<Vec3d> targets;
    std::vector<Vec3<T>> from;
    std::vector<char> kinematic;
  };
  struct EndTimes {
    double worker_ms = 0, repack_ms = 0, build_ms = 0, split_ms = 0, bind_ms = 0;
  };
  struct FrameBlade {  // the blade over this frame while a stroke is in the tissue (world, m)
    bool on = false;
    BladePose from, to;
  };

  // --- Set-up (host/sim/dissection_simulation.cpp) -----------------------------------------------------------
  void readTools();
  void setPbdParams();
  void buildOrgan();
  void setRegionSettings();
  void measureReferenceSphere();
  void installFirstModel();

  // --- The frame (host/sim/dissection_simulation.cpp) --------------------------------------------------------
  void startFrameTimers();
  void applyDueWork(double t0);
  void takeMouseBlade();
  PbdFrameInput<T> frameInput(double t0, double t1) const;
  std::string pbdRefusal(double frame_dt) const;
  void pbdFrame(double frame_dt, const PbdFrameInput<T>& in, FrameOutcome& out);
  void updateGraspers(double t0);
  bool coupled() const { return active_ && active_->region && active_->region->active(); }
  bool isKinematic(std::int32_t pbd) const {
    if (!active_ || !active_->region) return false;
    const std::int32_t b = active_->pbd_to_base[std::size_t(pbd)];
    return active_->region->role(b) == SphereRole::Interface;
  }
  // The scalpel is a capsule around its blade while a stroke is in the tissue (cutting.blade_radius_m > 0): spheres
  // (a PBD tool capsule) and nodal points (MlsSolver::setBladeContact) it covers are pushed out of it, what its
  // sweep cuts is cut.
  bool bladeContact() const { return frame_blade_.on && scene_.cutting.blade_radius_m > 0.0; }
  void appendBladeInput(PbdFrameInput<T>& in) const;

  // --- The PBD model (host/sim/dissection_simulation.cpp) ----------------------------------------------------
  MetaballPbdOptions pbdOptions(std::vector<double> known_cell_volumes, bool require_fixed_held) const;
  void installSpheres(MetaballModel m, PbdModel<T> built, const std::vector<Vec3d>& x, const std::vector<Vec3d>& v,
                      const std::vector<std::int32_t>& old_to_new, bool preloaded = false);

  // --- Strokes (host/sim/dissection_stroke.cpp) --------------------------------------------------------------
  void scriptedStrokes(double t0, double t1);
  void beginStroke(const BladePose& pose, int scripted);
  void extendStroke(const BladePose& pose);
  std::vector<std::int32_t> spheresEntered(const SweptSurface& strip) const;
  void completeStroke();
  void mouseStroke(const ToolEvent& e, const std::vector<Vec3d>& x, ToolResult& res);
  std::vector<const SweptSurface*> earlierCuts() const;

  // --- Conversions (host/sim/dissection_conversion.cpp) ------------------------------------------------------
  void launchConversion(std::unique_ptr<PendingConversion<T>> pc, std::vector<std::int32_t> hit);
  void applyConversion();
  void transferConversion(PendingConversion<T>& pc, NodalRegion& region, const std::vector<ConvertedSphereState>& st);
  void addConversionTimes(const NodalRegion& region);
  NodalRegionSettings regionSettings() const;
  ConvertedSphereState sphereState(std::int32_t b) const;
  bool directFrameFits(const PbdStepParams<T>& p) const;
  void preloadStrokePbd(StrokePbdPlan<T>& plan);
  void installStrokePbd(StrokePbdPlan<T>& p);

  // --- A stroke's end (host/sim/dissection_stroke_end.cpp) ---------------------------------------------------
  void endStroke();
  StrokeEndInput strokeEndInput(const ActiveStroke& a) const;
  void applyStrokeEnd();
  void installRepackedSpheres(ActiveStroke& a, const StrokeEndInput& in, StrokeEndResult& r, PbdModel<T>& built);
  void installCutSurface(StrokeEndResult& r);
  void recordCut(ActiveStroke& a, StrokeEndResult& r);

  // --- The surface (host/sim/dissection_surface.cpp) ---------------------------------------------------------
  void bindSurface();
  Vec3d skinSphereDisplacement(std::int32_t s, const Vec3d& p) const;
  void openSurface(double t0);

  // --- The coupled frame, section 5.3 (host/sim/dissection_coupled_frame.cpp) -------------------------------
  void coupledFrame(double frame_dt, const PbdFrameInput<T>& in, FrameOutcome& out);
  PbdStepParams<T> exchangeParams(double dt) const;
  InterfaceAnchors interfaceAnchors() const;
  bool advancePoints(int e, int K, double dt, FrameOutcome& out);
  PbdFrameInput<T> exchangeInput(int e, int K, const PbdFrameInput<T>& in, InterfaceAnchors& anchors);
  bool advanceSpheres(int e, int K, const PbdStepParams<T>& p, const PbdFrameInput<T>& ie, FrameOutcome& out);

  // --- The frame report (host/sim/dissection_report.cpp) -----------------------------------------------------
  void reportStages(FrameReport& rep, const FrameOutcome& out) const;
  void reportFailure(FrameReport& rep, const FrameOutcome& out) const;
  void report(FrameReport& rep, const MlsFrameStats& mls, int exchanges) const;
  void reportEnergies(FrameReport& rep) const;
  void reportStroke(FrameReport& rep, const MlsFrameStats& mls, int exchanges) const;
  void reportCuts(FrameReport& rep) const;
  void reportWork(FrameReport& rep) const;

  CompiledScene scene_;
  std::vector<ScriptedStroke> strokes_;
  std::vector<Grasper> graspers_, saved_graspers_;
  std::vector<ToolSpec> probes_;
  NodalRegionSettings region_;
  double reference_mass_ = 0.0, reference_radius_ = 0.0;  // kg, m: the organ's mean sphere before any cut
  std::shared_ptr<const pack::SurfaceDistance> tissue_;   // the organ's rest surface (inside test)
  std::string fill_note_;       // how the organ's spheres were filled and joined (buildSceneMetaballs)
  MetaballModel spheres_;       // the spheres of the PBD model (during a stroke: the base minus the cut ones)
  TriangleMesh rest_surface_;   // the surface after every cut so far (rest configuration) = surface_.mesh
  TriangleMesh collider_mesh_;  // the scene's colliders drawn around the organ (RenderLayers::colliders)
  // The split surface with its wall flags and binding probes; replaced, never changed in place (workers read it).
  std::shared_ptr<const CutSurfaceState> surface_;
  Skin skin_;
  std::vector<Vec3d> skin_rest_centres_;  // rest centres of the model the skin is bound to
  PbdModel<T> model_;
  std::unique_ptr<PbdBackend<T>> backend_;
  PbdStepParams<T> params_;
  PbdState<T> state_, saved_state_;
  std::unique_ptr<ActiveStroke> active_;
  // A stroke's end in the making (active_ is that stroke, its points still simulated).
  std::shared_ptr<PendingStrokeEnd<T>> ending_;
  bool last_end_here_ = false;  // the last applied end was computed on the frame's thread, the worker given up on
  std::unique_ptr<PendingConversion<T>> converting_;
  SurfaceOpening opening_;  // a surface opening in the making and the one shown (openSurface)
  int saved_frames_left_ = -1;
  std::string last_split_failure_;          // why the last applied cut left the surface unsplit (empty: it did not)
  EndTimes last_end_;                       // the worker's times of the last applied stroke end
  std::vector<SweptSurface> earlier_cuts_;  // every stroke finished so far (rest configuration)
  std::size_t last_points_ = 0, last_added_ = 0;
  RepackResult last_repack_;
  bool surface_split_ = false;
  int cuts_done_ = 0;
  long version_ = 0, saved_version_ = -1;  // topology version (every PBD rebuild)
  int surface_components_ = 1, sphere_components_ = 1;
  std::vector<std::uint8_t> wall_flags_;  // per rest_surface_ triangle: 1 = cut wall
  PbdMouseGrasp mouse_;                   // the viewer's grasp
  mutable CutLayerBinding cut_layers_;    // renderLayers' binding of the swept surfaces (rebuilt when they change)
  Timers timers_;
  double last_convert_ms_ = 0.0, mouse_cut_ms_ = 0.0, mouse_convert_ms_ = 0.0;
  FrameBlade frame_blade_;
  BladePose mouse_blade_from_, mouse_blade_to_;  // the mouse blade at the last frame's end and now (world)
  int base_substeps_ = 4;
  double substep_scale_ = 1.0, mls_safety_scale_ = 1.0;
  double time_ = 0, saved_time_ = 0;
  // CUDA with delayed conversions: the workers load each conversion's models into spare device buffers (the PBD
  // backend and the MLS solver before last) beside the frame; INCISION_NO_PRELOAD=1 loads them in the applying frame
  // instead (for A/B runs). Declared before the workers: a worker still loading it is joined before it goes.
  bool preload_ = false;
  std::unique_ptr<PbdBackend<T>> spare_backend_;
  // A stroke's end and its surface split, at idle priority until the end is due; declared late, joined early.
  StrokeEndWorkers<T> end_workers_;
  // A conversion's region half beside its PBD half (at normal priority: it is due at the next frame).
  BackgroundTask convert_worker_, prepare_pbd_worker_;
};

}  // namespace inc::dissection
