/* One file of a DICOM series, as scan_dicom.cpp reads it: the tags that
 * place and describe its image, and then its pixels. scan_read() reads
 * every file of a directory this way (scan_read_dicom()); the fuzz target
 * "dicom" feeds single files to it. */
#ifndef SPINDLE_TOOLS_SCAN_DICOM_H
#define SPINDLE_TOOLS_SCAN_DICOM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "scan_priv.h"

#ifdef __cplusplus
extern "C" {
#endif

/* An image's tags, checked: one frame of one grey sample per pixel (8 or
 * 16 bits allocated, Bits Stored from 1 to that with High Bit one below),
 * MONOCHROME2, Rows and Columns 1 to SCAN_MAX_DIM, a positive Pixel
 * Spacing, Image Orientation (Patient) of two unit, orthogonal vectors
 * (normalised here), a finite Image Position (Patient), a finite, non-zero
 * Rescale Slope (1 when absent) and finite Rescale Intercept (0). */
struct scan_dicom_slice {
	char series[65];         /* Series Instance UID */
	uint32_t rows, columns;  /* j and i */
	double pixel_spacing[2]; /* as the file has it: between rows (along j), then between columns (along i) */
	double orientation[6];   /* the row direction (along i), then the column direction (along j), LPS */
	double position[3];      /* of the first voxel's centre, LPS mm */
	double thickness;        /* Slice Thickness in mm, 0 when absent */
	struct scan_rescale rescale;
	unsigned bits_allocated, bits_stored;
	bool is_signed;
};

/* Reads path's tags up to its pixel data. 0 with *out filled; 1 for a
 * DICOM file that holds no image (no Rows: a DICOMDIR, a report), which a
 * series skips; -EINVAL (not DICOM, or an image that breaks the rules
 * above), or another -errno, with a message naming the file. */
int scan_dicom_read_slice(const char *path, struct scan_dicom_slice *out, char *err, size_t err_size);
/* How slice's pixels are stored: SCAN_STORED_U8, _U16 or _I16 (8-bit
 * signed pixels are widened to 16). */
enum scan_stored scan_dicom_stored(const struct scan_dicom_slice *slice);
/* Reads path's pixels (decompressed by GDCM when they are) into dst:
 * rows * columns voxels of scan_dicom_stored(slice), host order, with the
 * bits above Bits Stored cleared or sign-extended. The file must still
 * have slice's tags. 0, or -EINVAL (or another -errno) with a message. */
int scan_dicom_read_pixels(const char *path, const struct scan_dicom_slice *slice, void *dst, char *err,
			   size_t err_size);

#ifdef __cplusplus
}
#endif

#endif
