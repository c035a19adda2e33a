/*
 * cv_bridge.cpp — the one C++ file: a thin C interface over the parts of
 * OpenCV 4 that have no C API: the linear-RGB to CIE Lab conversion (segmentation features, Haindl &
 * Filip 2007, section II.A), and the 2D DFT and DCT (range-map integration,
 * section II.B). Nothing here throws across the boundary: every OpenCV
 * exception becomes an error text. (PNG/JPEG go through libpng and libjpeg
 * directly, io/png_jpeg*.c: imgcodecs alone loaded ~125 libraries.)
 */
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>

extern "C" {
#include "core/core.h"
#include "io/io.h"
}

static void set_error(char *errbuf, size_t errlen, const char *what)
{
    if (errbuf && errlen) {
        std::strncpy(errbuf, what, errlen - 1);
        errbuf[errlen - 1] = '\0';
    }
}

/* Runs body (returning 0 or -1 with errbuf set) so that no exception
 * crosses into C: every OpenCV exception becomes the error text. */
template <class Body> static int guarded(char *errbuf, size_t errlen, Body body)
{
    try {
        return body();
    } catch (const std::exception &e) {
        set_error(errbuf, errlen, e.what());
    } catch (...) {
        set_error(errbuf, errlen, "unknown OpenCV failure");
    }
    return -1;
}

/* Linear RGB (floats, interleaved, n pixels) to CIE L*a*b* (D65), using
 * OpenCV's linear-RGB conversion: our pixels are already linearised, so the
 * sRGB variant (COLOR_RGB2Lab) would apply the transfer function twice. */
extern "C" int btfcv_rgb_to_lab(const float *rgb, size_t n, float *lab, char *errbuf,
                                size_t errlen)
{
    return guarded(errbuf, errlen, [&]() -> int {
        if (n == 0)
            return 0;
        if (n > (size_t)INT32_MAX) {
            set_error(errbuf, errlen, "too many pixels");
            return -1;
        }
        /* OpenCV expects [0, 1]; values above 1 (highlights) are clamped so
         * that L stays in [0, 100]. The clamped copy is made a chunk at a
         * time on the stack: a call allocates nothing on the heap (OpenCV's
         * two temporaries of the whole image were fresh pages at every
         * image of an analysis, docs/datasets.md, "UBO2014 .btf files"). */
        const size_t CHUNK = 1024;
        float clipped[3 * 1024];
        for (size_t i0 = 0; i0 < n; i0 += CHUNK) {
            size_t m = n - i0 < CHUNK ? n - i0 : CHUNK;
            for (size_t j = 0; j < 3 * m; j++) {
                float v = rgb[3 * i0 + j];
                clipped[j] = v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v;
            }
            cv::Mat src(1, (int)m, CV_32FC3, clipped);
            cv::Mat dst(1, (int)m, CV_32FC3, lab + 3 * i0);
            cv::cvtColor(src, dst, cv::COLOR_LRGB2Lab);
        }
        return 0;
    });
}

/* 2D discrete Fourier transform of a complex w x h array in double precision
 * (re and im separate, row-major), in place. inverse != 0: the inverse,
 * scaled by 1/(w*h). Any size (OpenCV uses mixed radix). */
extern "C" int btfcv_dft2(double *re, double *im, int w, int h, int inverse, char *errbuf,
                          size_t errlen)
{
    return guarded(errbuf, errlen, [&]() -> int {
        cv::Mat planes[2] = {cv::Mat(h, w, CV_64F, re), cv::Mat(h, w, CV_64F, im)};
        cv::Mat z;
        cv::merge(planes, 2, z);
        cv::dft(z, z, inverse ? (cv::DFT_INVERSE | cv::DFT_SCALE) : 0);
        cv::Mat out[2];
        cv::split(z, out);
        out[0].copyTo(planes[0]);
        out[1].copyTo(planes[1]);
        return 0;
    });
}

/* 2D DCT-II (inverse != 0: DCT-III, its inverse) of a real w x h array in
 * place, orthonormal scaling as OpenCV defines it. OpenCV requires even
 * sizes (or 1); others are an error here. */
extern "C" int btfcv_dct2(double *a, int w, int h, int inverse, char *errbuf, size_t errlen)
{
    return guarded(errbuf, errlen, [&]() -> int {
        if ((w > 1 && (w & 1)) || (h > 1 && (h & 1))) {
            set_error(errbuf, errlen, "DCT needs even sizes");
            return -1;
        }
        cv::Mat m(h, w, CV_64F, a);
        cv::dct(m, m, inverse ? cv::DCT_INVERSE : 0);
        return 0;
    });
}
