"""Order of the gallery examples (``sphinx_gallery_conf["within_subsection_order"]``):
the order of the pipeline, data to studies; an example not listed goes last, by name."""

ORDER = (
    "plot_identify_synthetic.py",
    "plot_f16_identification.py",
    "plot_typical_section_flutter.py",
    "plot_goland_wing.py",
    "plot_goland_rfa.py",
    "plot_lco_branches.py",
    "plot_compleib_synthesis.py",
    "plot_order_certificate.py",
    "plot_seed_wing_pipeline.py",
    "plot_seed_wing_control_models.py",
    "plot_flutter_mode_residues.py",
    "plot_two_controllers.py",
    "plot_family_verification.py",
    "plot_wing_file.py",
    "plot_sweep.py",
    "plot_sensitivity.py",
)


class PipelineOrder:
    """Sort key: position in :data:`ORDER`, then the file name."""

    def __init__(self, src_dir: str):
        self.src_dir = src_dir

    def __call__(self, filename: str):
        return (ORDER.index(filename) if filename in ORDER else len(ORDER), filename)

    def __repr__(self) -> str:
        return f"<{self.__class__.__name__}>"
