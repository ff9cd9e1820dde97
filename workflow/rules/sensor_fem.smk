# The sensor stack in finite elements (paper Sec. III-C, Fig. 7 and 8b): quarter
# mesh at every refinement level, mesh convergence, modes (short and open
# circuit), harmonic response with the fitted R and the cable, band edges.

SENSOR_FEM_LEVELS = range(1, len(config["sensor_fem"]["refinement_multipliers"]) + 1)
SENSOR_FEM_MESH = (
    f"{RESULTS}/sensor/mesh/stack_L{config['sensor_fem']['mesh_level']}.vtk"
)

FIGURES.extend([f"{RESULTS}/figures/fig07.png", f"{RESULTS}/figures/fig08b.png"])
SCORECARD_PARTS.append(f"{RESULTS}/scorecard/sensor_fem.csv")
TARGETS.extend(
    [
        f"{RESULTS}/sensor/modal.json",
        f"{RESULTS}/sensor/harmonic.csv",
        f"{RESULTS}/sensor/band.json",
        f"{RESULTS}/sensor/convergence.csv",
    ]
)


rule sensor_mesh:
    output:
        meshes=expand(
            f"{RESULTS}/sensor/mesh/stack_L{{level}}.vtk", level=SENSOR_FEM_LEVELS
        ),
        json=f"{RESULTS}/sensor/mesh/mesh.json",
    log:
        f"{RESULTS}/logs/sensor_mesh.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_mesh.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("sensor_mesh", "workflow/scripts/sensor_mesh.py"),
    script:
        "../scripts/sensor_mesh.py"


rule sensor_convergence:
    input:
        meshes=expand(
            f"{RESULTS}/sensor/mesh/stack_L{{level}}.vtk", level=SENSOR_FEM_LEVELS
        ),
        modal_row=f"{RESULTS}/sensor/convergence_modal_level.json",
    output:
        csv=f"{RESULTS}/sensor/convergence.csv",
    log:
        f"{RESULTS}/logs/sensor_convergence.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_convergence.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=3200,
        runtime=2,
    params:
        **stage_params("sensor_convergence", "workflow/scripts/sensor_convergence.py"),
    script:
        "../scripts/sensor_convergence.py"


rule sensor_modal:
    input:
        mesh=SENSOR_FEM_MESH,
    output:
        json=f"{RESULTS}/sensor/modal.json",
        mode=f"{RESULTS}/sensor/first_axial_mode.npz",
        ritz=f"{RESULTS}/sensor/ritz_model.npz",
        convergence_row=f"{RESULTS}/sensor/convergence_modal_level.json",
    log:
        f"{RESULTS}/logs/sensor_modal.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_modal.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=3800,
        runtime=3,
    params:
        **stage_params("sensor_modal", "workflow/scripts/sensor_modal.py"),
    script:
        "../scripts/sensor_modal.py"


rule sensor_harmonic:
    input:
        ritz=f"{RESULTS}/sensor/ritz_model.npz",
        modal=f"{RESULTS}/sensor/modal.json",
        resistance=f"{RESULTS}/calibration/resistance.json",
        lowfreq=f"{RESULTS}/sensor/lowfreq.json",
    output:
        csv=f"{RESULTS}/sensor/harmonic.csv",
        band=f"{RESULTS}/sensor/band.json",
    log:
        f"{RESULTS}/logs/sensor_harmonic.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_harmonic.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("sensor_harmonic", "workflow/scripts/sensor_harmonic.py"),
    script:
        "../scripts/sensor_harmonic.py"


rule scorecard_sensor_fem:
    input:
        modal=f"{RESULTS}/sensor/modal.json",
        band=f"{RESULTS}/sensor/band.json",
        convergence=f"{RESULTS}/sensor/convergence.csv",
    output:
        csv=f"{RESULTS}/scorecard/sensor_fem.csv",
    log:
        f"{RESULTS}/logs/scorecard_sensor_fem.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/scorecard_sensor_fem.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params(
            "scorecard_sensor_fem", "workflow/scripts/scorecard_sensor_fem.py"
        ),
    script:
        "../scripts/scorecard_sensor_fem.py"


rule fig07:
    input:
        notebook="notebooks/fig07_sensor_mode.ipynb",
        modal=f"{RESULTS}/sensor/modal.json",
        mode=f"{RESULTS}/sensor/first_axial_mode.npz",
    output:
        figure=report(
            f"{RESULTS}/figures/fig07.png",
            caption="../report/fig07.rst",
            category="Sensor FEM",
        ),
        notebook=f"{RESULTS}/notebooks/fig07_sensor_mode.ipynb",
    log:
        f"{RESULTS}/logs/fig07.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig07.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("fig07", "notebooks/fig07_sensor_mode.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r modal {input.modal:q}"
        " -r mode {input.mode:q} -r figure {output.figure:q} > {log:q} 2>&1"


rule fig08b:
    input:
        notebook="notebooks/fig08b_sensor_harmonic.ipynb",
        harmonic=f"{RESULTS}/sensor/harmonic.csv",
        band=f"{RESULTS}/sensor/band.json",
    output:
        figure=report(
            f"{RESULTS}/figures/fig08b.png",
            caption="../report/fig08b.rst",
            category="Sensor FEM",
        ),
        notebook=f"{RESULTS}/notebooks/fig08b_sensor_harmonic.ipynb",
    log:
        f"{RESULTS}/logs/fig08b.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig08b.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("fig08b", "notebooks/fig08b_sensor_harmonic.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r harmonic {input.harmonic:q}"
        " -r band {input.band:q} -r figure {output.figure:q} > {log:q} 2>&1"
