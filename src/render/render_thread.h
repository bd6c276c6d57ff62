#pragma once
// Preparing a thread that renders in software beside the physics thread (the cameras' render
// thread, the viewer's main thread): a higher nice value (inherited by the threads llvmpipe starts
// from it) and, unless the user set LP_NUM_THREADS, one llvmpipe rasteriser fewer than the cores,
// so under contention the physics keeps its rate.
//
// Threading contract: the calling thread only (it changes that thread's nice value; the
// environment variable is process-wide and set only when absent).
namespace urlab::render {

// Sets LP_NUM_THREADS to the cores less one unless it is set. Call before creating a GL context.
void LimitSoftwareRasterThreads();
// Adds `nice_increment` to the calling thread's nice value for good; false when it could not.
bool LowerThreadPriority(int nice_increment);
// Both: call on the render thread before creating its OffscreenGl.
void PrepareRenderThread(int nice_increment);

}  // namespace urlab::render
