// Datasets as CSV: read, written and read back.

#include "fuzz_target.hpp"
#include "multicue/ml/dataset.hpp"

MULTICUE_FUZZ_TARGET(dataset_csv) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "input.csv");
    fuzz::AllowTypedErrors([&] {
        const ml::Dataset d = ml::LoadCsv(path);
        const auto copy = path.parent_path() / "copy.csv";
        ml::SaveCsv(d, copy);
        if (ml::LoadCsv(copy).rows() != d.rows()) {
            throw std::logic_error("a CSV dataset written from a read one reads back differently");
        }
    });
}
