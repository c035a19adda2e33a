/*
 * cv_bridge.cpp — the one C++ file: a thin C interface over the parts of
 * OpenCV 4 that have no C API (image decoding and encoding). Nothing here
 * throws across the boundary: every OpenCV exception becomes an error text.
 */
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdlib>
#include <cstring>
#include <exception>
#include <vector>

extern "C" {
#include "internal.h"
}

static void set_error(char *errbuf, size_t errlen, const char *what)
{
    if (errbuf && errlen) {
        std::strncpy(errbuf, what, errlen - 1);
        errbuf[errlen - 1] = '\0';
    }
}

/* Decodes a PNG/JPEG file as stored: 8- or 16-bit, 1 or 3 channels, RGB
 * order (OpenCV's BGR is swapped here so no caller sees it). Alpha dropped. */
extern "C" int btfcv_read(const char *path, int *w, int *h, int *c, int *depth16,
                          void **pixels, char *errbuf, size_t errlen)
{
    *pixels = nullptr;
    try {
        cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED | cv::IMREAD_ANYDEPTH |
                                         cv::IMREAD_ANYCOLOR);
        if (m.empty()) {
            set_error(errbuf, errlen, "cannot decode image");
            return -1;
        }
        if (m.depth() != CV_8U && m.depth() != CV_16U) {
            set_error(errbuf, errlen, "unsupported sample type (not 8- or 16-bit)");
            return -1;
        }
        cv::Mat rgb;
        switch (m.channels()) {
        case 1: rgb = m; break;
        case 3: cv::cvtColor(m, rgb, cv::COLOR_BGR2RGB); break;
        case 4: cv::cvtColor(m, rgb, cv::COLOR_BGRA2RGB); break;
        default:
            set_error(errbuf, errlen, "unsupported channel count");
            return -1;
        }
        if (!rgb.isContinuous())
            rgb = rgb.clone();
        size_t bytes = rgb.total() * rgb.elemSize();
        void *buf = std::malloc(bytes ? bytes : 1);
        if (!buf) {
            set_error(errbuf, errlen, "out of memory");
            return -1;
        }
        std::memcpy(buf, rgb.data, bytes);
        *w = rgb.cols;
        *h = rgb.rows;
        *c = rgb.channels();
        *depth16 = rgb.depth() == CV_16U;
        *pixels = buf;
        return 0;
    } catch (const std::exception &e) {
        set_error(errbuf, errlen, e.what());
    } catch (...) {
        set_error(errbuf, errlen, "unknown OpenCV failure");
    }
    return -1;
}

/* Encodes 8-bit RGB or grey pixels to a memory buffer (".png" or ".jpg"). */
extern "C" int btfcv_encode(const char *ext, int w, int h, int c,
                            const unsigned char *pixels, int jpeg_quality,
                            unsigned char **out, size_t *outlen, char *errbuf,
                            size_t errlen)
{
    *out = nullptr;
    *outlen = 0;
    try {
        cv::Mat m(h, w, c == 3 ? CV_8UC3 : CV_8UC1, const_cast<unsigned char *>(pixels));
        cv::Mat bgr;
        if (c == 3)
            cv::cvtColor(m, bgr, cv::COLOR_RGB2BGR);
        else
            bgr = m;
        std::vector<int> params;
        if (std::strcmp(ext, ".jpg") == 0) {
            params = {cv::IMWRITE_JPEG_QUALITY, jpeg_quality};
        } else {
            /* Level 3: files within a few % of level 9 at a fraction of the time. */
            params = {cv::IMWRITE_PNG_COMPRESSION, 3};
        }
        std::vector<unsigned char> buf;
        if (!cv::imencode(ext, bgr, buf, params)) {
            set_error(errbuf, errlen, "encoder failed");
            return -1;
        }
        unsigned char *copy = static_cast<unsigned char *>(std::malloc(buf.size() ? buf.size() : 1));
        if (!copy) {
            set_error(errbuf, errlen, "out of memory");
            return -1;
        }
        std::memcpy(copy, buf.data(), buf.size());
        *out = copy;
        *outlen = buf.size();
        return 0;
    } catch (const std::exception &e) {
        set_error(errbuf, errlen, e.what());
    } catch (...) {
        set_error(errbuf, errlen, "unknown OpenCV failure");
    }
    return -1;
}
