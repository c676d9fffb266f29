"""implicit_sim's core in Python (doc/python.md): load a scene, step it, read its state and contacts as numpy arrays.

    import implicit_sim
    model = implicit_sim.load_scene("scenes/p3_sphere_on_two_spheres.urdf")
    options = implicit_sim.StepperOptions()
    options.h = 0.01
    data = implicit_sim.Data(model)
    state = implicit_sim.State.initial(model)
    report = implicit_sim.step(model, options, state, data)

The ROS messages of the node stay where they were (implicit_sim.msg, implicit_sim.srv).
"""
from implicit_sim._core import (Data, Model, NewtonOptions, State, StepperOptions, StepReport, WarmStart,
                                clear_warm_start, joint_position, joint_velocity, kinetic_energy, load_scene,
                                load_scene_string, option_table, restore_warm_start, save_warm_start, step,
                                surface_mesh, wrench_at_point, write_step_case)

__all__ = ["Data", "Model", "NewtonOptions", "State", "StepperOptions", "StepReport", "WarmStart", "clear_warm_start",
           "joint_position", "joint_velocity", "kinetic_energy", "load_scene", "load_scene_string", "option_table",
           "restore_warm_start", "save_warm_start", "step", "surface_mesh", "wrench_at_point", "write_step_case"]
