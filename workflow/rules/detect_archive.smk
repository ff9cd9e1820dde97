# piezobearing detect over an archive of recordings (docs/guides/detect.md, "Many records at once"): a job per
# record of detect_archive.folder, so a rerun detects only new or changed records, then the table and the
# trend. Outside rule all: `snakemake detect_archive --configfile my_archive.yaml` (a large archive on the
# cluster profile, `--profile workflow/profiles/<cluster>`).
from piezobearing.io.archive import archive_records, record_rig

ARCHIVE = archive_records(config["detect_archive"])


rule detect_record:
    input:
        record=lambda wc: ARCHIVE[wc.name],
        rig=lambda wc: record_rig(ARCHIVE[wc.name], config["detect_archive"]),
    output:
        row=f"{RESULTS}/detect_archive/{{name}}/row.json",
    log:
        f"{RESULTS}/logs/detect_record/{{name}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/detect_record/{{name}}.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc, input: 500 + 20 * int(input.size_mb),
        runtime=2,
    params:
        **stage_params("detect_record", "workflow/scripts/detect_record.py"),
    script:
        "../scripts/detect_record.py"


rule detect_archive:
    input:
        rows=expand(f"{RESULTS}/detect_archive/{{name}}/row.json", name=sorted(ARCHIVE)),
    output:
        csv=f"{RESULTS}/detect_archive/detections.csv",
        trend=report(
            f"{RESULTS}/detect_archive/trend.png",
            caption="../report/detect_archive.rst",
            category="Recordings",
        ),
    log:
        f"{RESULTS}/logs/detect_archive.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/detect_archive.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("detect_archive", "workflow/scripts/detect_archive.py"),
    script:
        "../scripts/detect_archive.py"
