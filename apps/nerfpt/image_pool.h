// Images a shot's frames cycle through: the render loop takes one, and the frame's writer gives it back when its
// files are written (the last holder releases it), so a 1080p float frame (25 MB) is not allocated and
// zero-filled again for every frame, and stays page-locked for the GPU's downloads (docs/benchmarks.md, issue
// 26's shot benchmark).
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "core/image.h"

namespace npt::cli {

class ImagePool {
  public:
    struct Slot {
        Image image;  // empty the first time: the renderer sizes it
        // What the renderer keeps about the image's storage (SceneRenderer::pin); declared after the image, so
        // it is released before the storage is freed.
        std::shared_ptr<void> pin;
    };

    // A free slot, given back to the pool when the last shared_ptr to it goes, even after the pool is gone.
    std::shared_ptr<Slot> take() {
        std::unique_ptr<Slot> slot;
        {
            std::lock_guard<std::mutex> lock(m_free->mutex);
            if (!m_free->slots.empty()) {
                slot = std::move(m_free->slots.back());
                m_free->slots.pop_back();
            }
        }
        if (!slot) slot = std::make_unique<Slot>();
        return std::shared_ptr<Slot>(slot.release(), [free = m_free](Slot* returned) {
            std::lock_guard<std::mutex> lock(free->mutex);
            free->slots.emplace_back(returned);
        });
    }

  private:
    struct Free {
        std::mutex mutex;
        std::vector<std::unique_ptr<Slot>> slots;
    };
    std::shared_ptr<Free> m_free = std::make_shared<Free>();
};

}  // namespace npt::cli
