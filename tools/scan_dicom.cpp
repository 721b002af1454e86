/* DICOM series for scan.h: a directory of files, one slice each, read with
 * GDCM (the only C++ of Spindle; scan_dicom.h is its C interface) from
 * the fds scan_open() opened (tools/scan.c lists the directory). Each
 * file's tags are read up to its pixel data and checked
 * (scan_dicom_read_slice()); the images must all belong to one series and
 * agree in size, pixel spacing, orientation and pixel format. The slices
 * are ordered by their Image Position (Patient) along the normal of the
 * image plane (the cross product of the row and column directions of Image
 * Orientation (Patient)), must be evenly spaced (within 1%) along a line,
 * and only then are their pixels read (GDCM decompresses them when they
 * are compressed) straight into the volume. DICOM's patient space is LPS;
 * to_ras negates x and y. GDCM's exceptions stop at this file's C
 * functions; its assert()s, which Debian's build keeps, abort the process
 * on some malformed files, so untrusted directories belong in a sandboxed
 * child (docs/volumes.md, "Untrusted files and the libraries"). */
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <exception>
#include <fcntl.h>
#include <istream>
#include <memory>
#include <new>
#include <streambuf>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include <gdcmDataSet.h>
#include <gdcmImageReader.h>
#include <gdcmReader.h>
#include <gdcmTrace.h>

#include "scan_dicom.h"

namespace
{

/* An open file as a stream for GDCM, read with pread() (nothing is
 * opened here: in spindlectl's loader the files come open, and open()
 * fails), seekable. It notes a read cut short by the end of the file:
 * GDCM reads a truncated Pixel Data element, pads it with zeros and says
 * nothing. A short read of more than 8 bytes (a value, never a tag or a
 * length), or of part of anything, is a truncated file; reading nothing
 * where the next tag would be is its normal end. A read error is noted
 * too (error), and ends the stream. */
class fd_buf : public std::streambuf
{
      public:
	bool cut = false;
	int error = 0;

	fd_buf(int fd, uint64_t size) : fd_(fd), size_(static_cast<off_type>(size))
	{
		setg(buf_, buf_, buf_);
	}

      protected:
	int_type underflow() override
	{
		if (gptr() < egptr())
			return traits_type::to_int_type(*gptr());
		off_type at = start_ + (egptr() - eback());
		ssize_t n;
		do
			n = pread(fd_, buf_, sizeof(buf_), static_cast<off_t>(at));
		while (n < 0 && errno == EINTR);
		start_ = at;
		setg(buf_, buf_, buf_ + (n > 0 ? n : 0));
		if (n < 0)
			error = errno;
		return n > 0 ? traits_type::to_int_type(*gptr()) : traits_type::eof();
	}

	std::streamsize xsgetn(char *s, std::streamsize n) override
	{
		std::streamsize got = std::streambuf::xsgetn(s, n);
		if (got < n && (got > 0 || n > 8))
			cut = true;
		return got;
	}

	pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override
	{
		off_type base = dir == std::ios_base::beg   ? 0
				: dir == std::ios_base::cur ? start_ + (gptr() - eback())
							    : size_;
		return seekpos(pos_type(base + off), which);
	}

	pos_type seekpos(pos_type pos, std::ios_base::openmode which) override
	{
		off_type at = static_cast<off_type>(pos);
		if (!(which & std::ios_base::in) || at < 0)
			return pos_type(off_type(-1));
		if (at >= start_ && at <= start_ + (egptr() - eback()))
			setg(eback(), eback() + (at - start_), egptr());
		else {
			start_ = at;
			setg(buf_, buf_, buf_);
		}
		return pos;
	}

      private:
	int fd_;
	off_type size_;
	off_type start_ = 0; /* the file offset of eback() */
	char buf_[1 << 16];
};

/* Points reader at the file through buf. */
void use_stream(fd_buf &buf, std::istream &is, gdcm::Reader &reader)
{
	is.rdbuf(&buf);
	reader.SetStream(is);
}

/* A read error of the file, if buf met one: -errno with a message. */
int read_error(const fd_buf &buf, const char *path, char *err, size_t err_size)
{
	return buf.error ? scan_fail(err, err_size, -buf.error, path, "%s", strerror(buf.error)) : 0;
}

/* GDCM says nothing on stderr: every failure is reported here. */
void quiet()
{
	gdcm::Trace::SetDebug(false);
	gdcm::Trace::SetWarning(false);
	gdcm::Trace::SetError(false);
}

/* The bytes of an element with a value, or false. */
bool raw_value(const gdcm::DataSet &ds, uint16_t group, uint16_t element, const char **p, size_t *len)
{
	const gdcm::Tag tag(group, element);
	if (!ds.FindDataElement(tag))
		return false;
	const gdcm::ByteValue *bv = ds.GetDataElement(tag).GetByteValue();
	if (!bv || !bv->GetPointer() || bv->GetLength() == 0)
		return false;
	*p = bv->GetPointer();
	*len = bv->GetLength();
	return true;
}

/* A text value without its padding (spaces, NULs). */
bool text(const gdcm::DataSet &ds, uint16_t group, uint16_t element, std::string &out)
{
	const char *p;
	size_t len;
	if (!raw_value(ds, group, element, &p, &len))
		return false;
	out.assign(p, len);
	size_t start = out.find_first_not_of(" \0", 0, 2), end = out.find_last_not_of(" \0", std::string::npos, 2);
	out = start == std::string::npos ? std::string() : out.substr(start, end - start + 1);
	return !out.empty();
}

/* One number of a DS or IS value: spaces around it, a leading '+'. */
bool number(std::string part, double *v)
{
	size_t start = part.find_first_not_of(' '), end = part.find_last_not_of(' ');
	if (start == std::string::npos)
		return false;
	part = part.substr(start, end - start + 1);
	if (part[0] == '+')
		part.erase(0, 1);
	const char *first = part.data(), *last = first + part.size();
	auto res = std::from_chars(first, last, *v);
	return res.ec == std::errc() && res.ptr == last && std::isfinite(*v);
}

/* A DS (or IS) value of exactly n finite numbers. */
bool numbers(const gdcm::DataSet &ds, uint16_t group, uint16_t element, double *v, size_t n)
{
	std::string s;
	if (!text(ds, group, element, s))
		return false;
	size_t pos = 0;
	for (size_t k = 0; k < n; k++) {
		size_t next = s.find('\\', pos);
		if ((next == std::string::npos) != (k == n - 1))
			return false;
		if (!number(s.substr(pos, next == std::string::npos ? std::string::npos : next - pos), &v[k]))
			return false;
		pos = next + 1;
	}
	return true;
}

/* A US value (two bytes; GDCM gives those of a big-endian data set
 * swapped to host order, as it gives the pixels). */
bool us(const gdcm::DataSet &ds, uint16_t group, uint16_t element, unsigned *v)
{
	const char *p;
	size_t len;
	uint16_t u;
	if (!raw_value(ds, group, element, &p, &len) || len != 2)
		return false;
	memcpy(&u, p, 2);
	*v = u;
	return true;
}

/* One file's tags, for the checks below. */
struct tags {
	const gdcm::DataSet &ds;
	const char *path;
	char *err;
	size_t err_size;
};

int check_series(const tags &t, scan_dicom_slice *out)
{
	std::string uid;
	if (!text(t.ds, 0x0020, 0x000e, uid) || uid.size() >= sizeof(out->series))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "no valid Series Instance UID");
	memcpy(out->series, uid.c_str(), uid.size() + 1);
	return 0;
}

/* One frame, one grey sample per pixel, MONOCHROME2. */
int check_kind(const tags &t)
{
	unsigned samples = 1;
	double frames = 1;
	std::string photometric;
	if (t.ds.FindDataElement(gdcm::Tag(0x0028, 0x0002)) && !us(t.ds, 0x0028, 0x0002, &samples))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "a bad Samples per Pixel");
	if (samples != 1)
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "%u samples per pixel: only grey images are read",
				 samples);
	if (t.ds.FindDataElement(gdcm::Tag(0x0028, 0x0008)) && !numbers(t.ds, 0x0028, 0x0008, &frames, 1))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "a bad Number of Frames");
	if (frames != 1)
		return scan_fail(t.err, t.err_size, -EINVAL, t.path,
				 "%g frames: multi-frame images are not read (one file per slice is)", frames);
	if (!text(t.ds, 0x0028, 0x0004, photometric) || photometric != "MONOCHROME2")
		return scan_fail(t.err, t.err_size, -EINVAL, t.path,
				 "photometric interpretation %s: only MONOCHROME2 is read",
				 photometric.empty() ? "(none)" : photometric.c_str());
	return 0;
}

/* Bits Allocated 8 or 16, Bits Stored 1 to that, High Bit one below it. */
int check_bits(const tags &t, scan_dicom_slice *out)
{
	unsigned allocated = 0, stored = 0, high = 0, representation = 0;
	if (!us(t.ds, 0x0028, 0x0100, &allocated) || (allocated != 8 && allocated != 16))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "Bits Allocated %u: 8 or 16 are read", allocated);
	if (!us(t.ds, 0x0028, 0x0101, &stored))
		stored = allocated;
	if (!us(t.ds, 0x0028, 0x0102, &high))
		high = stored - 1;
	if (t.ds.FindDataElement(gdcm::Tag(0x0028, 0x0103)) && !us(t.ds, 0x0028, 0x0103, &representation))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "a bad Pixel Representation");
	if (stored < 1 || stored > allocated || high != stored - 1 || representation > 1)
		return scan_fail(
			t.err, t.err_size, -EINVAL, t.path,
			"Bits Stored %u, High Bit %u, Pixel Representation %u with %u bits allocated: not read", stored,
			high, representation, allocated);
	out->bits_allocated = allocated;
	out->bits_stored = stored;
	out->is_signed = representation == 1;
	return 0;
}

int check_size(const tags &t, scan_dicom_slice *out)
{
	unsigned rows = 0, columns = 0;
	if (!us(t.ds, 0x0028, 0x0011, &columns))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "Rows without Columns");
	us(t.ds, 0x0028, 0x0010, &rows);
	if (rows < 1 || columns < 1 || rows > SCAN_MAX_DIM || columns > SCAN_MAX_DIM)
		return scan_fail(t.err, t.err_size, rows > SCAN_MAX_DIM || columns > SCAN_MAX_DIM ? -E2BIG : -EINVAL,
				 t.path, "an image of %u rows and %u columns: 1 to %u are read", rows, columns,
				 SCAN_MAX_DIM);
	out->rows = rows;
	out->columns = columns;
	return 0;
}

double dot(const double *a, const double *b)
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Two unit vectors (within 1e-3, then normalised), orthogonal (1e-3). */
bool unit_pair(double *v)
{
	double a = std::sqrt(dot(v, v)), b = std::sqrt(dot(v + 3, v + 3));
	if (std::fabs(a - 1) > 1e-3 || std::fabs(b - 1) > 1e-3)
		return false;
	for (int n = 0; n < 3; n++) {
		v[n] /= a;
		v[3 + n] /= b;
	}
	return std::fabs(dot(v, v + 3)) < 1e-3;
}

int check_geometry(const tags &t, scan_dicom_slice *out)
{
	double *ps = out->pixel_spacing;
	if (!numbers(t.ds, 0x0028, 0x0030, ps, 2) || !(ps[0] > 0 && ps[1] > 0))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "no valid Pixel Spacing (two numbers > 0)");
	if (!numbers(t.ds, 0x0020, 0x0037, out->orientation, 6) || !unit_pair(out->orientation))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path,
				 "no valid Image Orientation (Patient) (two orthogonal unit vectors)");
	if (!numbers(t.ds, 0x0020, 0x0032, out->position, 3))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "no valid Image Position (Patient)");
	if (!numbers(t.ds, 0x0018, 0x0050, &out->thickness, 1) || !(out->thickness > 0))
		out->thickness = 0;
	return 0;
}

int check_rescale(const tags &t, scan_dicom_slice *out)
{
	out->rescale = { 1, 0 };
	bool has_slope = t.ds.FindDataElement(gdcm::Tag(0x0028, 0x1053));
	bool has_inter = t.ds.FindDataElement(gdcm::Tag(0x0028, 0x1052));
	if ((has_slope && !numbers(t.ds, 0x0028, 0x1053, &out->rescale.slope, 1)) ||
	    (has_inter && !numbers(t.ds, 0x0028, 0x1052, &out->rescale.inter, 1)) || out->rescale.slope == 0)
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "a bad Rescale Slope or Intercept");
	return 0;
}

/* All the checks of one image's tags; 1 for a file without an image. */
int check_slice(const tags &t, scan_dicom_slice *out)
{
	unsigned rows;
	if (!t.ds.FindDataElement(gdcm::Tag(0x0028, 0x0010)))
		return 1;
	if (!us(t.ds, 0x0028, 0x0010, &rows))
		return scan_fail(t.err, t.err_size, -EINVAL, t.path, "a bad Rows");
	int ret = check_series(t, out);
	if (ret == 0)
		ret = check_kind(t);
	if (ret == 0)
		ret = check_bits(t, out);
	if (ret == 0)
		ret = check_size(t, out);
	if (ret == 0)
		ret = check_geometry(t, out);
	if (ret == 0)
		ret = check_rescale(t, out);
	return ret;
}

int read_slice(const scan_input &in, scan_dicom_slice *out, char *err, size_t err_size)
{
	quiet();
	gdcm::Reader reader;
	fd_buf buf(in.fd, in.size);
	std::istream is(nullptr);
	use_stream(buf, is, reader);
	bool ok = reader.ReadUpToTag(gdcm::Tag(0x7fe0, 0x0010));
	if (int ret = read_error(buf, in.path, err, err_size))
		return ret;
	if (!ok)
		return scan_fail(err, err_size, -EINVAL, in.path, "not a DICOM file (GDCM cannot read it)");
	if (buf.cut)
		return scan_fail(err, err_size, -EINVAL, in.path,
				 "truncated (an element ends past the end of the file)");
	return check_slice(tags{ reader.GetFile().GetDataSet(), in.path, err, err_size }, out);
}

/* GDCM's image agrees with the tags read before. */
bool same_image(const gdcm::Image &image, const scan_dicom_slice *s)
{
	const gdcm::PixelFormat &pf = image.GetPixelFormat();
	return image.GetColumns() == s->columns && image.GetRows() == s->rows &&
	       (image.GetNumberOfDimensions() == 2 || image.GetDimension(2) == 1) && pf.GetSamplesPerPixel() == 1 &&
	       pf.GetBitsAllocated() == s->bits_allocated && pf.GetPixelRepresentation() == (s->is_signed ? 1 : 0);
}

/* dst's voxels (n of them) from GDCM's buffer: the bits over Bits Stored
 * cleared or sign-extended, 8-bit signed pixels widened. */
void take_pixels(const std::vector<char> &buf, const scan_dicom_slice *s, void *dst, size_t n)
{
	unsigned shift = s->bits_allocated == 8 ? 8 : 16 - s->bits_stored;
	for (size_t i = 0; i < n; i++) {
		if (s->bits_allocated == 8) {
			uint8_t v = static_cast<uint8_t>(buf[i]) & static_cast<uint8_t>((1u << s->bits_stored) - 1);
			if (!s->is_signed) {
				static_cast<uint8_t *>(dst)[i] = v;
				continue;
			}
			unsigned sh = 8 - s->bits_stored;
			int16_t w = static_cast<int8_t>(static_cast<uint8_t>(v << sh)) >> sh;
			memcpy(static_cast<uint8_t *>(dst) + 2 * i, &w, 2);
			continue;
		}
		uint16_t v;
		memcpy(&v, buf.data() + 2 * i, 2);
		v = static_cast<uint16_t>(v << shift);
		if (s->is_signed) {
			int16_t w = static_cast<int16_t>(static_cast<int16_t>(v) >> shift);
			memcpy(static_cast<uint8_t *>(dst) + 2 * i, &w, 2);
		} else {
			v = static_cast<uint16_t>(v >> shift);
			memcpy(static_cast<uint8_t *>(dst) + 2 * i, &v, 2);
		}
	}
}

int read_pixels(const scan_input &in, const scan_dicom_slice *s, void *dst, char *err, size_t err_size)
{
	quiet();
	gdcm::ImageReader reader;
	fd_buf file(in.fd, in.size);
	std::istream is(nullptr);
	use_stream(file, is, reader);
	bool ok = reader.Read();
	if (int ret = read_error(file, in.path, err, err_size))
		return ret;
	if (!ok)
		return scan_fail(err, err_size, -EINVAL, in.path, "GDCM cannot read the image (damaged?)");
	if (file.cut)
		return scan_fail(err, err_size, -EINVAL, in.path,
				 "truncated (its pixel data ends past the end of the file)");
	const gdcm::Image &image = reader.GetImage();
	size_t n = static_cast<size_t>(s->rows) * s->columns;
	if (!same_image(image, s) || image.GetBufferLength() != n * (s->bits_allocated / 8))
		return scan_fail(err, err_size, -EINVAL, in.path, "the image differs from what its tags said");
	std::vector<char> buf(image.GetBufferLength());
	if (!image.GetBuffer(buf.data()))
		return scan_fail(err, err_size, -EINVAL, in.path,
				 "GDCM cannot decode the pixel data (truncated or damaged?)");
	take_pixels(buf, s, dst, n);
	return 0;
}

/* ---- the series ---- */

struct slice_file {
	const scan_input *in;
	scan_dicom_slice s;
	double along; /* the position along the slice normal */
};

/* b agrees with a in everything but its position and rescale. */
int check_same(const slice_file &a, const slice_file &b, const char *dir, char *err, size_t err_size)
{
	const scan_dicom_slice &x = a.s, &y = b.s;
	if (strcmp(x.series, y.series) != 0)
		return scan_fail(err, err_size, -EINVAL, dir,
				 "holds more than one series (%s and %s differ in Series Instance UID)", a.in->path,
				 b.in->path);
	const char *what = nullptr;
	if (x.rows != y.rows || x.columns != y.columns)
		what = "Rows and Columns";
	else if (std::fabs(x.pixel_spacing[0] - y.pixel_spacing[0]) > 1e-4 * x.pixel_spacing[0] ||
		 std::fabs(x.pixel_spacing[1] - y.pixel_spacing[1]) > 1e-4 * x.pixel_spacing[1])
		what = "Pixel Spacing";
	else if (!std::equal(x.orientation, x.orientation + 6, y.orientation,
			     [](double p, double q) { return std::fabs(p - q) <= 1e-4; }))
		what = "Image Orientation (Patient)";
	else if (scan_dicom_stored(&x) != scan_dicom_stored(&y))
		what = "pixel format";
	if (what)
		return scan_fail(err, err_size, -EINVAL, dir, "%s and %s differ in %s", a.in->path, b.in->path, what);
	return 0;
}

/* The images of the directory, their tags read and checked. */
int read_series(const char *dir, const scan_input *files, size_t count, std::vector<slice_file> &slices, char *err,
		size_t err_size)
{
	int ret = 0;
	for (size_t n = 0; ret == 0 && n < count; n++) {
		slice_file f{ &files[n], {}, 0 };
		int r = read_slice(files[n], &f.s, err, err_size);
		if (r < 0)
			return r;
		if (r == 0 && !slices.empty())
			ret = check_same(slices[0], f, dir, err, err_size);
		if (r == 0)
			slices.push_back(f);
	}
	if (ret == 0 && slices.empty())
		return scan_fail(err, err_size, -ENODATA, dir, "no DICOM images in the directory");
	return ret;
}

void cross(const double *a, const double *b, double *c)
{
	c[0] = a[1] * b[2] - a[2] * b[1];
	c[1] = a[2] * b[0] - a[0] * b[2];
	c[2] = a[0] * b[1] - a[1] * b[0];
}

/* No two slices at one position, and even gaps along the normal: the one
 * furthest from their mean within 1% of it. */
int check_gaps(const std::vector<slice_file> &sl, double mean, const char *dir, char *err, size_t err_size)
{
	size_t worst = 1;
	for (size_t k = 1; k < sl.size(); k++) {
		double gap = sl[k].along - sl[k - 1].along;
		if (gap < 1e-3 * sl[0].s.pixel_spacing[0])
			return scan_fail(err, err_size, -EINVAL, dir,
					 "%s and %s lie at the same position (more than one acquisition?)",
					 sl[k - 1].in->path, sl[k].in->path);
		if (std::fabs(gap - mean) > std::fabs(sl[worst].along - sl[worst - 1].along - mean))
			worst = k;
	}
	double gap = sl[worst].along - sl[worst - 1].along;
	if (std::fabs(gap - mean) > 0.01 * mean)
		return scan_fail(err, err_size, -EINVAL, dir,
				 "slices are not evenly spaced: %.4g mm between %s and %s, %.4g mm on average (a "
				 "missing slice?)",
				 gap, sl[worst - 1].in->path, sl[worst].in->path, mean);
	return 0;
}

/* Every position on the line from the first by whole steps (within 1%). */
int check_line(const std::vector<slice_file> &sl, const double *step, const char *dir, char *err, size_t err_size)
{
	double len = std::sqrt(dot(step, step));
	for (size_t k = 0; k < sl.size(); k++) {
		double d[3];
		for (int a = 0; a < 3; a++)
			d[a] = sl[k].s.position[a] - (sl[0].s.position[a] + static_cast<double>(k) * step[a]);
		if (std::sqrt(dot(d, d)) > 0.01 * len)
			return scan_fail(err, err_size, -EINVAL, dir, "%s lies off the line of the other slices",
					 sl[k].in->path);
	}
	return 0;
}

/* Sorts the slices along the normal and gives the step between them. */
int order(std::vector<slice_file> &sl, double *step, const char *dir, char *err, size_t err_size)
{
	double normal[3];
	cross(sl[0].s.orientation, sl[0].s.orientation + 3, normal);
	for (slice_file &f : sl)
		f.along = dot(f.s.position, normal);
	std::stable_sort(sl.begin(), sl.end(),
			 [](const slice_file &a, const slice_file &b) { return a.along < b.along; });
	if (sl.size() == 1) {
		if (sl[0].s.thickness <= 0)
			return scan_fail(err, err_size, -EINVAL, dir, "one slice (%s) without a Slice Thickness",
					 sl[0].in->path);
		for (int a = 0; a < 3; a++)
			step[a] = normal[a] * sl[0].s.thickness;
		return 0;
	}
	double mean = (sl.back().along - sl.front().along) / static_cast<double>(sl.size() - 1);
	int ret = check_gaps(sl, mean, dir, err, err_size);
	for (int a = 0; a < 3; a++)
		step[a] = (sl.back().s.position[a] - sl.front().s.position[a]) / static_cast<double>(sl.size() - 1);
	return ret == 0 ? check_line(sl, step, dir, err, err_size) : ret;
}

/* dims, spacing and to_ras (LPS to RAS: x and y negated). */
void set_geometry(scan *out, const scan_dicom_slice &s, const double *step, size_t count)
{
	static const double flip[3] = { -1, -1, 1 };
	out->dims[0] = s.columns;
	out->dims[1] = s.rows;
	out->dims[2] = static_cast<uint32_t>(count);
	out->spacing[0] = s.pixel_spacing[1];
	out->spacing[1] = s.pixel_spacing[0];
	out->spacing[2] = std::sqrt(dot(step, step));
	for (int a = 0; a < 3; a++) {
		out->to_ras[a] = flip[a] * s.orientation[a] * out->spacing[0];
		out->to_ras[4 + a] = flip[a] * s.orientation[3 + a] * out->spacing[1];
		out->to_ras[8 + a] = flip[a] * step[a];
		out->to_ras[12 + a] = flip[a] * s.position[a];
	}
	out->to_ras[3] = out->to_ras[7] = out->to_ras[11] = 0;
	out->to_ras[15] = 1;
}

/* Every slice's pixels, in order, into one buffer; then the volume. */
int read_volume(const std::vector<slice_file> &sl, scan *out, const char *dir, char *err, size_t err_size)
{
	uint64_t voxels;
	int ret = scan_check_dims(dir, out->dims, &voxels, err, err_size);
	if (ret != 0)
		return ret;
	enum scan_stored stored = scan_dicom_stored(&sl[0].s);
	size_t per_slice = static_cast<size_t>(out->dims[0]) * out->dims[1] * scan_stored_size(stored);
	std::unique_ptr<uint8_t, decltype(&free)> buf(static_cast<uint8_t *>(scan_samples_alloc(per_slice * sl.size())),
						      &free);
	if (!buf)
		return scan_fail(err, err_size, -ENOMEM, dir, "out of memory for %zu bytes", per_slice * sl.size());
	std::vector<scan_rescale> r(sl.size());
	for (size_t k = 0; ret == 0 && k < sl.size(); k++) {
		ret = read_pixels(*sl[k].in, &sl[k].s, buf.get() + k * per_slice, err, err_size);
		r[k] = sl[k].s.rescale;
	}
	if (ret != 0)
		return ret;
	return scan_finish(out, stored, buf.release(), r.data(), static_cast<uint32_t>(r.size()), dir, err, err_size);
}

int read_dicom(const char *dir, const scan_input *files, size_t count, scan *out, char *err, size_t err_size)
{
	std::vector<slice_file> sl;
	double step[3];
	int ret = read_series(dir, files, count, sl, err, err_size);
	if (ret == 0 && sl.size() > SCAN_MAX_DIM)
		return scan_fail(err, err_size, -E2BIG, dir, "%zu slices: at most %u are read", sl.size(),
				 SCAN_MAX_DIM);
	if (ret == 0)
		ret = order(sl, step, dir, err, err_size);
	if (ret != 0)
		return ret;
	set_geometry(out, sl[0].s, step, sl.size());
	ret = read_volume(sl, out, dir, err, err_size);
	if (ret == 0)
		scan_describe(out, "DICOM", nullptr);
	return ret;
}

/* Runs f, turning what GDCM or the library throws into an error. */
template <typename F> int guarded(const char *path, char *err, size_t err_size, F f)
{
	try {
		return f();
	} catch (const std::bad_alloc &) {
		return scan_fail(err, err_size, -ENOMEM, path, "out of memory");
	} catch (const std::exception &e) {
		return scan_fail(err, err_size, -EINVAL, path, "GDCM failed: %s", e.what());
	} catch (...) {
		return scan_fail(err, err_size, -EINVAL, path, "GDCM failed");
	}
}

} // namespace

extern "C" enum scan_stored scan_dicom_stored(const struct scan_dicom_slice *slice)
{
	if (slice->bits_allocated == 8 && !slice->is_signed)
		return SCAN_STORED_U8;
	return slice->is_signed ? SCAN_STORED_I16 : SCAN_STORED_U16;
}

/* path opened for the calls below, which take a scan_input. */
template <typename F> int on_file(const char *path, char *err, size_t err_size, F f)
{
	int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
	struct stat st;
	if (fd < 0)
		return scan_fail(err, err_size, -errno, path, "%s", strerror(errno));
	int e = fstat(fd, &st) != 0 ? errno : S_ISREG(st.st_mode) ? 0 : EINVAL;
	if (e) {
		close(fd);
		return scan_fail(err, err_size, -e, path, "%s", e == EINVAL ? "not a regular file" : strerror(e));
	}
	scan_input in{ const_cast<char *>(path), fd, static_cast<uint64_t>(st.st_size) };
	int ret = f(in);
	close(fd);
	return ret;
}

extern "C" int scan_dicom_read_slice(const char *path, struct scan_dicom_slice *out, char *err, size_t err_size)
{
	memset(out, 0, sizeof(*out));
	return guarded(path, err, err_size, [&] {
		return on_file(path, err, err_size,
			       [&](const scan_input &in) { return read_slice(in, out, err, err_size); });
	});
}

extern "C" int scan_dicom_read_pixels(const char *path, const struct scan_dicom_slice *slice, void *dst, char *err,
				      size_t err_size)
{
	return guarded(path, err, err_size, [&] {
		return on_file(path, err, err_size,
			       [&](const scan_input &in) { return read_pixels(in, slice, dst, err, err_size); });
	});
}

extern "C" int scan_read_dicom(const char *dir, const struct scan_input *files, size_t count, struct scan *out,
			       char *err, size_t err_size)
{
	return guarded(dir, err, err_size, [&] { return read_dicom(dir, files, count, out, err, err_size); });
}
