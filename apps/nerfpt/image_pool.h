// Images a shot's frames cycle through: the render loop takes one, and the frame's writer gives it back when its
// files are written (the last holder releases it), so a 1080p float frame (25 MB) is not allocated and
// zero-filled again for every frame (docs/benchmarks.md, issue 26's shot benchmark).
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "core/image.h"

namespace npt::cli {

class ImagePool {
  public:
    // A free image (empty the first times: the renderer sizes it), given back to the pool when the last
    // shared_ptr to it goes, even after the pool itself is gone.
    std::shared_ptr<Image> take() {
        std::unique_ptr<Image> image;
        {
            std::lock_guard<std::mutex> lock(m_free->mutex);
            if (!m_free->images.empty()) {
                image = std::move(m_free->images.back());
                m_free->images.pop_back();
            }
        }
        if (!image) image = std::make_unique<Image>();
        return std::shared_ptr<Image>(image.release(), [free = m_free](Image* returned) {
            std::lock_guard<std::mutex> lock(free->mutex);
            free->images.emplace_back(returned);
        });
    }

  private:
    struct Free {
        std::mutex mutex;
        std::vector<std::unique_ptr<Image>> images;
    };
    std::shared_ptr<Free> m_free = std::make_shared<Free>();
};

}  // namespace npt::cli
