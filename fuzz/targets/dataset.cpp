// Datasets in the binary format (.mcd): read, written and read back.

#include "multicue/ml/dataset.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(dataset) {
    using namespace multicue;
    const auto path = fuzz::WriteContainerInput(fuzz::Bytes(data, size), "MCUEDSET",
                                                ml::kDatasetFormatVersion, "input.mcd");
    fuzz::AllowTypedErrors([&] {
        const ml::Dataset d = ml::LoadDataset(path);
        const auto copy = path.parent_path() / "copy.mcd";
        ml::SaveDataset(d, copy);
        if (ml::LoadDataset(copy).rows() != d.rows()) {
            throw std::logic_error("a dataset written from a read one reads back differently");
        }
    });
}
