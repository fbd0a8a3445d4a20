// dsreg — the only translation unit that includes ITK (see itk_bridge.hpp). No Eigen here.
#include "itk_bridge.hpp"

#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkHDF5ImageIO.h>
#include <itkImage.h>
#include <itkImageIOBase.h>
#include <itkImageSeriesReader.h>
#include <itkMetaDataObject.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>
#include <itkTIFFImageIO.h>
#include <itkVTKImageIO.h>

#include <gdcmTrace.h>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <new>
#include <vector>

#include "dsreg/error.hpp"

namespace dsreg::volume_io_detail {

namespace {

[[noreturn]] void fail_path(const std::string& path, const std::string& problem) { throw Error(path + ": " + problem); }

/// ITK and GDCM print warnings and errors on stderr; dsreg reports problems itself.
void silence_itk_warnings() {
    static const bool silenced = [] {
        itk::Object::GlobalWarningDisplayOff();
        gdcm::Trace::WarningOff();
        gdcm::Trace::ErrorOff();
        return true;
    }();
    (void)silenced;
}

itk::ImageIOBase::Pointer make_io(ItkFormat format) {
    switch (format) {
    case ItkFormat::Nifti: return itk::NiftiImageIO::New().GetPointer();
    case ItkFormat::Nrrd: return itk::NrrdImageIO::New().GetPointer();
    case ItkFormat::MetaImage: return itk::MetaImageIO::New().GetPointer();
    case ItkFormat::Tiff: return itk::TIFFImageIO::New().GetPointer();
    case ItkFormat::Hdf5: return itk::HDF5ImageIO::New().GetPointer();
    case ItkFormat::VtkImage: return itk::VTKImageIO::New().GetPointer();
    case ItkFormat::DicomFile: return itk::GDCMImageIO::New().GetPointer();
    }
    return nullptr;
}

/// ITK's message without its decorations ("ITK ERROR: NiftiImageIO(0x55...): ", source paths),
/// on one line and bounded.
std::string clean_itk_message(const std::string& description) {
    std::string text = description;
    const std::string marker = "ITK ERROR: ";
    if (const std::size_t at = text.find(marker); at != std::string::npos) text.erase(0, at + marker.size());
    if (const std::size_t open = text.find("(0x"); open != std::string::npos && open < 40) {  // "ClassName(0x1234): "
        const std::size_t close = text.find("): ", open);
        if (close != std::string::npos) text.erase(0, close + 3);
    }
    for (char& c : text)
        if (c == '\n' || c == '\r' || c == '\t') c = ' ';
    // teem's chains ("[nrrd] nrrdLoad: trouble reading ... [nrrd] _nrrdRead: trouble ..."): keep
    // the pieces that say something, without the function names.
    if (text.find("[nrrd] ") != std::string::npos) {
        std::string kept;
        std::size_t at = text.find("[nrrd] ");
        while (at != std::string::npos) {
            const std::size_t next = text.find("[nrrd] ", at + 7);
            std::string piece = text.substr(at + 7, (next == std::string::npos ? text.size() : next) - at - 7);
            if (const std::size_t colon = piece.find(": "); colon != std::string::npos && piece.find(' ') > colon)
                piece.erase(0, colon + 2);
            while (!piece.empty() && piece.back() == ' ') piece.pop_back();
            if (!piece.empty() && piece != "trouble" && piece.rfind("trouble reading", 0) != 0 &&
                piece.rfind("trouble reading NRRD file", 0) != 0)
                kept += (kept.empty() ? "" : "; ") + piece;
            at = next;
        }
        if (!kept.empty()) text = kept;
    }
    while (!text.empty() && text.back() == ' ') text.pop_back();
    if (text.size() > 300) text = text.substr(0, 300) + "...";
    return text.empty() ? "unknown ITK error" : text;
}

/// Runs `action`, translating ITK's exceptions (and running out of memory) into dsreg::Error, and
/// whatever the libraries under ITK throw through it: HDF5's C++ exceptions (H5::Exception,
/// not a std::exception) left ITK's HDF5 reader on a damaged file and ended the process in
/// std::terminate (found by mutating a small .h5 by hand).
template <typename Action>
void translated(const std::string& path, const std::string& doing, Action&& action) {
    try {
        action();
    } catch (const itk::ExceptionObject& error) {
        fail_path(path, doing + ": " + clean_itk_message(error.GetDescription()));
    } catch (const std::bad_alloc&) {
        fail_path(path, "not enough memory to " + doing.substr(doing.find(' ') + 1));
    } catch (const Error&) {
        throw;  // ours, already naming the file
    } catch (const std::exception& error) {
        fail_path(path, doing + ": " + clean_itk_message(error.what()));
    } catch (...) {
        fail_path(path, doing + ": the library that decodes it failed (a damaged file?)");
    }
}

std::string lower_case(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

bool host_big_endian() {
    const std::uint16_t probe = 1;
    std::uint8_t first;
    std::memcpy(&first, &probe, 1);
    return first == 0;
}

std::string sample_name(const SampleFormat& sample) {
    const char* kind = sample.kind == SampleKind::Unsigned ? "uint" : sample.kind == SampleKind::Signed ? "int" : "float";
    return kind + std::to_string(8 * sample.bytes);
}

/// What `query` returns, or `fallback` where ITK throws: it does for the unknown types that a
/// malformed header leaves (a MetaImage whose ElementType line is garbled, found by fuzzing), and
/// the header's own checks, not ITK, then say what is wrong with it.
template <class T, class Query>
T itk_or(T fallback, Query query) {
    try {
        return query();
    } catch (const itk::ExceptionObject&) {
        return fallback;
    }
}

/// The value type of an ImageIO as dsreg's SampleFormat (host byte order: ITK swaps bytes).
void describe_component(const itk::ImageIOBase& io, ImageHeader& header) {
    using Component = itk::IOComponentEnum;
    const Component type = io.GetComponentType();
    const int bytes = itk_or(0, [&] { return static_cast<int>(io.GetComponentSize()); });
    header.sample.bytes = bytes;
    header.sample.big_endian = host_big_endian();
    header.value_type_supported = bytes == 1 || bytes == 2 || bytes == 4 || bytes == 8;
    switch (type) {
    case Component::UCHAR:
    case Component::USHORT:
    case Component::UINT:
    case Component::ULONG:
    case Component::ULONGLONG: header.sample.kind = SampleKind::Unsigned; break;
    case Component::CHAR:
    case Component::SHORT:
    case Component::INT:
    case Component::LONG:
    case Component::LONGLONG: header.sample.kind = SampleKind::Signed; break;
    case Component::FLOAT:
    case Component::DOUBLE: header.sample.kind = SampleKind::Float; break;
    default: header.value_type_supported = false; break;
    }
    header.value_type = header.value_type_supported
                            ? sample_name(header.sample)
                            : itk_or(std::string("unknown"), [&] { return itk::ImageIOBase::GetComponentTypeAsString(type); });
}

ImageHeader header_of(const itk::ImageIOBase& io, const std::string& format) {
    ImageHeader header;
    header.format = format;
    for (unsigned d = 0; d < io.GetNumberOfDimensions(); ++d) {
        header.sizes.push_back(static_cast<std::int64_t>(io.GetDimensions(d)));
        header.spacing.push_back(io.GetSpacing(d));
        header.origin.push_back(io.GetOrigin(d));
        header.direction.push_back(io.GetDirection(d));
    }
    header.components = io.GetNumberOfComponents();
    header.pixel_type = lower_case(itk_or(std::string("unknown"), [&] { return itk::ImageIOBase::GetPixelTypeAsString(io.GetPixelType()); }));
    describe_component(io, header);
    return header;
}

itk::ImageIOBase::Pointer open_header(const std::string& path, ItkFormat format) {
    silence_itk_warnings();
    itk::ImageIOBase::Pointer io = make_io(format);
    const std::string name = itk_format_name(format);
    translated(path, "cannot read the " + name + " header", [&] {
        if (!io->CanReadFile(path.c_str())) fail_path(path, "not a file ITK can read as " + name);
        io->SetFileName(path);
        io->ReadImageInformation();
    });
    return io;
}

/// The region of slices [first, first + count) of an image of `sizes` (all of it below 3-D).
itk::ImageIORegion slice_region(const std::vector<std::int64_t>& sizes, std::int64_t first, std::int64_t count) {
    itk::ImageIORegion region(static_cast<unsigned>(sizes.size()));
    for (unsigned d = 0; d < sizes.size(); ++d) {
        region.SetIndex(d, d == 2 ? first : 0);
        region.SetSize(d, static_cast<itk::SizeValueType>(d == 2 ? count : sizes[d]));
    }
    return region;
}

itk::IOComponentEnum component_of(const SampleFormat& sample) {
    using Component = itk::IOComponentEnum;
    switch (sample.kind) {
    case SampleKind::Unsigned:
        return sample.bytes == 1 ? Component::UCHAR : sample.bytes == 2 ? Component::USHORT : sample.bytes == 4 ? Component::UINT
                                                                                                               : Component::ULONGLONG;
    case SampleKind::Signed:
        return sample.bytes == 1 ? Component::CHAR : sample.bytes == 2 ? Component::SHORT : sample.bytes == 4 ? Component::INT
                                                                                                             : Component::LONGLONG;
    case SampleKind::Float: return sample.bytes == 4 ? Component::FLOAT : Component::DOUBLE;
    }
    return Component::UNKNOWNCOMPONENTTYPE;
}

/// Geometry and value type of a 3-D scalar image on `io`.
void describe_image(itk::ImageIOBase& io, const ImageHeader& image) {
    io.SetNumberOfDimensions(3);
    for (unsigned d = 0; d < 3; ++d) {
        io.SetDimensions(d, static_cast<itk::SizeValueType>(image.sizes[d]));
        io.SetSpacing(d, image.spacing[d]);
        io.SetOrigin(d, image.origin[d]);
        io.SetDirection(d, image.direction[d]);
    }
    io.SetPixelType(itk::IOPixelEnum::SCALAR);
    io.SetComponentType(component_of(image.sample));
    io.SetNumberOfComponents(1);
}

void write_with_io(itk::ImageIOBase& io, const std::string& path, const ImageHeader& image, const void* buffer) {
    io.SetFileName(path);
    io.SetIORegion(slice_region(image.sizes, 0, image.sizes[2]));
    io.WriteImageInformation();
    io.Write(buffer);
}

}  // namespace

const char* itk_format_name(ItkFormat format) {
    switch (format) {
    case ItkFormat::Nifti: return "NIfTI";
    case ItkFormat::Nrrd: return "NRRD";
    case ItkFormat::MetaImage: return "MetaImage";
    case ItkFormat::Tiff: return "TIFF";
    case ItkFormat::Hdf5: return "HDF5";
    case ItkFormat::VtkImage: return "VTK image";
    case ItkFormat::DicomFile: return "DICOM";
    }
    return "";
}

namespace {

/// What the child process of check_dicom_in_child_process does with one file: GDCM's reading of
/// it as the parent's reader will do it (its header, then its voxels up to 256 MiB), with `io`,
/// made before the fork. Exceptions are the parent's reader's to report.
void read_dicom_file_quietly(itk::GDCMImageIO& io, const std::string& path) {
    constexpr itk::SizeValueType kLargestChildRead = itk::SizeValueType(256) << 20;
    try {
        if (!io.CanReadFile(path.c_str())) return;
        io.SetFileName(path);
        io.ReadImageInformation();
        const itk::SizeValueType bytes = io.GetImageSizeInBytes();
        if (bytes > kLargestChildRead) return;
        std::vector<char> buffer(static_cast<std::size_t>(bytes));
        std::vector<std::int64_t> sizes;
        for (unsigned d = 0; d < io.GetNumberOfDimensions(); ++d) sizes.push_back(std::int64_t(io.GetDimensions(d)));
        io.SetIORegion(slice_region(sizes, 0, sizes.size() >= 3 ? sizes[2] : 1));
        io.Read(buffer.data());
    } catch (...) {
    }
}

}  // namespace

void check_dicom_in_child_process(const std::vector<std::string>& paths) {
    if (paths.empty()) return;
    // Made here, not in the child: ITK's object factory takes a lock, which another thread of
    // this process may hold at the fork (a child has only the forking thread: it would wait forever).
    const itk::GDCMImageIO::Pointer io = itk::GDCMImageIO::New();
    int channel[2];  // the child writes the index of each file before reading it
    if (pipe(channel) != 0) return;  // no child process: the read that follows decides alone
    const pid_t child = fork();
    if (child < 0) {
        close(channel[0]), close(channel[1]);
        return;
    }
    if (child == 0) {
        // The child dies of what would have killed the parent (and not through a sanitizer's
        // or fuzzer's handler, which would report it as a crash of the parent).
        for (const int signal_number : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) std::signal(signal_number, SIG_DFL);
        const int null_device = open("/dev/null", O_WRONLY);  // GDCM's assertion text: the parent reports
        if (null_device >= 0) dup2(null_device, STDERR_FILENO), dup2(null_device, STDOUT_FILENO);
        close(channel[0]);
        silence_itk_warnings();
        for (std::uint32_t index = 0; index < paths.size(); ++index) {
            if (write(channel[1], &index, sizeof index) != ssize_t(sizeof index)) _exit(1);
            read_dicom_file_quietly(*io, paths[index]);
        }
        _exit(0);  // no exit handlers, no flush of the parent's buffers
    }
    close(channel[1]);
    std::uint32_t index = 0, last = 0;
    for (ssize_t got; (got = read(channel[0], &index, sizeof index)) != 0;) {
        if (got == ssize_t(sizeof index)) last = index;
        else if (got < 0 && errno != EINTR) break;
    }
    close(channel[0]);
    int status = 0;
    while (waitpid(child, &status, 0) < 0)
        if (errno != EINTR) return;
    if (WIFSIGNALED(status) && last < paths.size())
        fail_path(paths[last], "GDCM, the DICOM library, aborted reading this file (signal " + std::to_string(WTERMSIG(status)) +
                                   "): damaged or unsupported DICOM data");
}

ImageHeader read_itk_header(const std::string& path, ItkFormat format) {
    const itk::ImageIOBase::Pointer io = open_header(path, format);
    return header_of(*io, itk_format_name(format));
}

// ----------------------------------------------------------------------------------------------
// ItkImageReader

struct ItkImageReader::Io {
    itk::ImageIOBase::Pointer io;
};

ItkImageReader::ItkImageReader(const std::string& path, ItkFormat format)
    : path_(path), format_(format), io_(std::make_unique<Io>()) {
    io_->io = open_header(path, format);
    header_ = header_of(*io_->io, itk_format_name(format));
}

ItkImageReader::~ItkImageReader() = default;

bool ItkImageReader::can_stream() const { return io_->io->CanStreamRead() && header_.sizes.size() >= 3; }

void ItkImageReader::read_slices(std::int64_t first, std::int64_t count, void* buffer) {
    translated(path_, std::string("cannot read the ") + itk_format_name(format_) + " voxels", [&] {
        io_->io->SetIORegion(header_.sizes.size() >= 3 ? slice_region(header_.sizes, first, count)
                                                       : slice_region(header_.sizes, 0, 1));
        io_->io->Read(buffer);
    });
}

// ----------------------------------------------------------------------------------------------
// DicomSeriesReader

struct DicomSeriesReader::Series {
    using Image = itk::Image<double, 3>;
    using Reader = itk::ImageSeriesReader<Image>;
    itk::GDCMImageIO::Pointer io = itk::GDCMImageIO::New();
    Reader::Pointer reader = Reader::New();
};

DicomSeriesReader::DicomSeriesReader(const std::string& folder) : folder_(folder), series_(std::make_unique<Series>()) {
    silence_itk_warnings();
    translated(folder, "cannot read the DICOM series", [&] {
        const itk::GDCMSeriesFileNames::Pointer names = itk::GDCMSeriesFileNames::New();
        names->SetDirectory(folder);
        const std::vector<std::string>& uids = names->GetSeriesUIDs();
        if (uids.empty()) fail_path(folder, "no DICOM image series in this folder (no file GDCM reads as a DICOM image)");
        if (uids.size() > 1) {
            std::string list;
            for (std::size_t s = 0; s < uids.size() && s < 3; ++s) list += (s ? ", " : "") + uids[s];
            fail_path(folder, "the folder holds " + std::to_string(uids.size()) + " DICOM series (" + list +
                                  (uids.size() > 3 ? ", ..." : "") + "): give a folder holding only the series to read");
        }
        files_ = names->GetFileNames(uids.front());
        series_->reader->SetImageIO(series_->io);
        series_->reader->SetFileNames(files_);
        series_->reader->ForceOrthogonalDirectionOff();
        series_->reader->MetaDataDictionaryArrayUpdateOff();
        series_->reader->UpdateOutputInformation();
    });
    header_ = header_of(*series_->io, "DICOM series");  // pixel and value type of the files
    const Series::Image* output = series_->reader->GetOutput();
    const Series::Image::RegionType largest = output->GetLargestPossibleRegion();
    header_.sizes.clear();
    header_.spacing.clear();
    header_.origin.clear();
    header_.direction.clear();
    for (unsigned d = 0; d < 3; ++d) {
        header_.sizes.push_back(static_cast<std::int64_t>(largest.GetSize(d)));
        header_.spacing.push_back(output->GetSpacing()[d]);
        header_.origin.push_back(output->GetOrigin()[d]);
        header_.direction.push_back({output->GetDirection()[0][d], output->GetDirection()[1][d], output->GetDirection()[2][d]});
    }
}

DicomSeriesReader::~DicomSeriesReader() = default;

void DicomSeriesReader::read_slices(std::int64_t first, std::int64_t count, double* buffer) {
    Series::Image* output = series_->reader->GetOutput();
    translated(folder_, "cannot read the DICOM series", [&] {
        Series::Image::RegionType region = output->GetLargestPossibleRegion();
        region.SetIndex(2, first);
        region.SetSize(2, static_cast<itk::SizeValueType>(count));
        output->SetRequestedRegion(region);
        series_->reader->Update();
        const Series::Image::RegionType buffered = output->GetBufferedRegion();
        if (buffered.GetIndex(2) > first || buffered.GetIndex(2) + static_cast<std::int64_t>(buffered.GetSize(2)) < first + count)
            fail_path(folder_, "ITK's series reader did not read the slices asked for");
        // Copy the slices asked for out of the buffered region (which may be larger).
        const std::size_t slice = static_cast<std::size_t>(region.GetSize(0) * region.GetSize(1));
        const double* start = output->GetBufferPointer() + static_cast<std::size_t>(first - buffered.GetIndex(2)) * slice;
        std::copy(start, start + slice * static_cast<std::size_t>(count), buffer);
        double deviation = 0;
        if (itk::ExposeMetaData<double>(output->GetMetaDataDictionary(), "ITK_non_uniform_sampling_deviation", deviation))
            deviation_ = std::max(deviation_, deviation);
    });
}

// ----------------------------------------------------------------------------------------------
// Writers

void write_itk_image(const std::string& path, ItkFormat format, const ImageHeader& image, const void* buffer, bool compress) {
    silence_itk_warnings();
    const itk::ImageIOBase::Pointer io = make_io(format);
    describe_image(*io, image);
    io->SetUseCompression(compress);
    translated(path, std::string("cannot write the ") + itk_format_name(format) + " image",
               [&] { write_with_io(*io, path, image, buffer); });
}

void write_itk_dicom_slice(const std::string& path, const ImageHeader& slice, const void* buffer,
                           const std::vector<std::pair<std::string, std::string>>& tags) {
    silence_itk_warnings();
    const itk::GDCMImageIO::Pointer io = itk::GDCMImageIO::New();
    io->KeepOriginalUIDOn();
    itk::MetaDataDictionary& dictionary = io->GetMetaDataDictionary();
    for (const auto& [tag, value] : tags) itk::EncapsulateMetaData<std::string>(dictionary, tag, value);
    describe_image(*io, slice);
    translated(path, "cannot write the DICOM slice", [&] { write_with_io(*io, path, slice, buffer); });
}

}  // namespace dsreg::volume_io_detail
