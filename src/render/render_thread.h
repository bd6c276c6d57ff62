#pragma once
// Preparing a thread that renders in software beside the physics thread: a higher nice value
// (inherited by the threads llvmpipe starts from it) and, unless the user set LP_NUM_THREADS,
// one llvmpipe rasteriser fewer than the cores, so under contention the physics keeps its rate.
// Call on the render thread before creating its OffscreenGl.
//
// Threading contract: the calling thread only (it changes that thread's nice value; the
// environment variable is process-wide and set only when absent).
namespace urlab::render {

void PrepareRenderThread(int nice_increment);

}  // namespace urlab::render
