"""The parts of a Kratos MPM case (10.4 MPMApplication) that the cantilever generators share.

`clamp_and_gravity(g)`: the processes of gen_cantilever.py and gen_cantilever_3d.py, every grid
node of the sub model part DISPLACEMENT_Support fixed and gravity g along -y on the material
points; `project_parameters(name, solver, end_time, g)`: ProjectParameters.json with them.
"""


def clamp_and_gravity(g):
    return {"constraints_process_list": [{
        "python_module": "assign_vector_variable_process", "kratos_module": "KratosMultiphysics",
        "Parameters": {"model_part_name": "Background_Grid.DISPLACEMENT_Support", "variable_name": "DISPLACEMENT",
                       "constrained": [True, True, True], "value": [0.0, 0.0, 0.0], "interval": [0.0, "End"]}}],
        "gravity": [{"python_module": "assign_gravity_to_material_point_process",
                     "kratos_module": "KratosMultiphysics.MPMApplication",
                     "process_name": "AssignGravityToMaterialPointProcess",
                     "Parameters": {"model_part_name": "MPM_Material", "modulus": g,
                                    "direction": [0.0, -1.0, 0.0]}}]}


def project_parameters(name, solver, end_time, g):
    return {"problem_data": {"problem_name": name, "parallel_type": "OpenMP", "start_time": 0.0,
                             "end_time": end_time, "echo_level": 0},
            "solver_settings": solver,
            "processes": clamp_and_gravity(g)}
