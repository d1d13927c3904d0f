# The validated mission of the 2017 thesis (Appendix C), ported to Python 3.
# Only two things changed: the Python 2 `print "..."` statements became print() calls,
# and the typo `angle:-90` became `angle=-90`. Everything else is as published,
# including the `sucess` spelling and the "Rotate 180 degrees" comment for -90.
import executive_engine_api as api


def runMission():
    print("Starting mission")

    print("Taking off...")
    result = api.executeBehavior('TAKE_OFF')
    print("Take off finished with status: %s" % result)

    print("Activating visual marker recognition...")
    api.activateBehavior('PAY_ATTENTION_TO_VISUAL_MARKERS')

    print("Move to a higher position")
    result = api.executeBehavior('GO_TO_POINT', relative_coordinates=[0, 0, 0.5])
    print("Go to point finished with status: %s" % result)

    print("Memorizing current point...")
    sucess, unification = api.consultBelief('position(self, (?X, ?Y, ?Z))')
    if sucess:
        print("Position memorized correctly")
        x, y, z = unification['X'], unification['Y'], unification['Z']
    else:
        print("Position unknown, landing...")
        result = api.executeBehavior('LAND')
        print("Landed with status: %s" % result)
        return

    print("Move to the target point")
    result = api.executeBehavior('GO_TO_POINT', coordinates=[3, 5.5, 1.3])
    print("Go to point finished with status: %s" % result)

    print("Rotate 180 degrees")
    result = api.executeBehavior('ROTATE', angle=-90)
    print("Rotate finished with status: %s" % result)

    print("Returning home")
    result = api.executeBehavior('GO_TO_POINT', coordinates=[x, y, z])
    print("Go to point finished with status: %s" % result)

    print("Deactivating visual marker recognition...")
    api.inhibitBehavior('PAY_ATTENTION_TO_VISUAL_MARKERS')
    print("Deactivated")

    print("Landing...")
    result = api.executeBehavior('LAND')
    print("Land finished with status: %s " % result)

    return True
