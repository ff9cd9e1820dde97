# The bearing and its housing (paper Sec. III-A, IV, Fig. 3): the 4-DOF
# lumped-parameter model's roller loads, the housing mesh, the transient FEM
# that turns them into the sensor's contact force; the mesh convergence study,
# the sampling-phase study of the step 1/(36 BPFO), and the scorecard rows.

BEARING_CASES = ["healthy", "faulty"]

FIGURES.append(f"{RESULTS}/figures/fig03.png")
SCORECARD_PARTS.append(f"{RESULTS}/scorecard/bearing.csv")
TARGETS.extend(
    [f"{RESULTS}/bearing/sensor_force_{c}.csv" for c in BEARING_CASES]
    + [
        f"{RESULTS}/bearing/kinematics.json",
        f"{RESULTS}/bearing/mesh_convergence.json",
        f"{RESULTS}/bearing/sampling_phase.json",
    ]
)


rule bearing_lpm:
    output:
        kinematics=f"{RESULTS}/bearing/kinematics.json",
        npz_healthy=f"{RESULTS}/bearing/contact_forces_healthy.npz",
        npz_faulty=f"{RESULTS}/bearing/contact_forces_faulty.npz",
        csv_healthy=f"{RESULTS}/bearing/contact_forces_healthy.csv",
        csv_faulty=f"{RESULTS}/bearing/contact_forces_faulty.csv",
        json=f"{RESULTS}/bearing/lpm.json",
    log:
        f"{RESULTS}/logs/bearing_lpm.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/bearing_lpm.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("bearing_lpm", "workflow/scripts/bearing_lpm.py"),
    script:
        "../scripts/bearing_lpm.py"


rule housing_mesh:
    output:
        npz=f"{RESULTS}/bearing/housing_mesh_{{case}}.npz",
        vtk=f"{RESULTS}/bearing/housing_mesh_{{case}}.vtk",
        json=f"{RESULTS}/bearing/housing_mesh_{{case}}.json",
    log:
        f"{RESULTS}/logs/housing_mesh_{{case}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/housing_mesh_{{case}}.tsv"
    wildcard_constraints:
        case="healthy|faulty",
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("housing_mesh", "workflow/scripts/housing_mesh.py"),
    script:
        "../scripts/housing_mesh.py"


rule housing_transient:
    input:
        mesh=f"{RESULTS}/bearing/housing_mesh_{{case}}.npz",
        contact=f"{RESULTS}/bearing/contact_forces_{{case}}.npz",
    output:
        csv=f"{RESULTS}/bearing/sensor_force_{{case}}.csv",
        modes=f"{RESULTS}/bearing/housing_modes_{{case}}.json",
        json=f"{RESULTS}/bearing/housing_transient_{{case}}.json",
        influence=f"{RESULTS}/bearing/influence_line_{{case}}.csv",
        # the quasi-static force on this mesh: housing_convergence's row of housing.mesh_level
        quasi_static=f"{RESULTS}/bearing/quasi_static_{{case}}.npz",
    log:
        f"{RESULTS}/logs/housing_transient_{{case}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/housing_transient_{{case}}.tsv"
    wildcard_constraints:
        case="healthy|faulty",
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=2300,
        runtime=2,
    params:
        **stage_params("housing_transient", "workflow/scripts/housing_transient.py"),
    script:
        "../scripts/housing_transient.py"


rule housing_convergence:
    input:
        contact=f"{RESULTS}/bearing/contact_forces_healthy.npz",
        # the level housing.mesh_level, solved by housing_transient_healthy (not factorised twice)
        quasi_static=f"{RESULTS}/bearing/quasi_static_healthy.npz",
    output:
        json=f"{RESULTS}/bearing/mesh_convergence.json",
        csv=f"{RESULTS}/bearing/mesh_convergence.csv",
    log:
        f"{RESULTS}/logs/housing_convergence.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/housing_convergence.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=5900,
        runtime=4,
    params:
        **stage_params("housing_convergence", "workflow/scripts/housing_convergence.py"),
    script:
        "../scripts/housing_convergence.py"


rule bearing_sampling:
    input:
        contact=f"{RESULTS}/bearing/contact_forces_faulty.npz",
        influence=f"{RESULTS}/bearing/influence_line_faulty.csv",
    output:
        json=f"{RESULTS}/bearing/sampling_phase.json",
    log:
        f"{RESULTS}/logs/bearing_sampling.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/bearing_sampling.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("bearing_sampling", "workflow/scripts/bearing_sampling.py"),
    script:
        "../scripts/bearing_sampling.py"


rule fig03:
    input:
        notebook="notebooks/fig03_housing_mesh.ipynb",
        healthy=f"{RESULTS}/bearing/housing_mesh_healthy.npz",
        faulty=f"{RESULTS}/bearing/housing_mesh_faulty.npz",
    output:
        figure=report(
            f"{RESULTS}/figures/fig03.png",
            caption="../report/fig03.rst",
            category="Bearing and housing",
        ),
        notebook=f"{RESULTS}/notebooks/fig03_housing_mesh.ipynb",
    log:
        f"{RESULTS}/logs/fig03.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig03.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("fig03", "notebooks/fig03_housing_mesh.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r healthy {input.healthy:q}"
        " -r faulty {input.faulty:q} -r figure {output.figure:q} > {log:q} 2>&1"


rule scorecard_bearing:
    input:
        kinematics=f"{RESULTS}/bearing/kinematics.json",
        lpm=f"{RESULTS}/bearing/lpm.json",
        healthy=f"{RESULTS}/bearing/housing_transient_healthy.json",
        faulty=f"{RESULTS}/bearing/housing_transient_faulty.json",
        convergence=f"{RESULTS}/bearing/mesh_convergence.json",
        sampling=f"{RESULTS}/bearing/sampling_phase.json",
    output:
        csv=f"{RESULTS}/scorecard/bearing.csv",
    log:
        f"{RESULTS}/logs/scorecard_bearing.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/scorecard_bearing.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("scorecard_bearing", "workflow/scripts/scorecard_bearing.py"),
    script:
        "../scripts/scorecard_bearing.py"
