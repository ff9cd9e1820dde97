"""The record formats the readers take, by file suffix: a table, no reader.

Kept apart from the readers (:mod:`.formats`, which loads pandas and scipy.io) so that listing an archive's
records (:mod:`.archive`, the workflow's parse) loads none of them.
"""

#: File extensions the record reader understands, and what they are.
RECORD_FORMATS = {
    ".csv": "comma-separated text with a header",
    ".mat": "MATLAB v5 (scipy.io) or v7.3 (HDF5, h5py)",
    ".uff": "universal file, dataset 58 (pyuff)",
    ".unv": "universal file, dataset 58 (pyuff)",
    ".tdms": "NI TDMS (npTDMS)",
    ".wav": "WAV (scipy.io.wavfile)",
}
