MODULE Ballbar
    ! Ballbar test of the source paper: the ball on the tool visits discrete points
    ! of a semicircle (radius 100 mm, 10 degree steps) in a plane inclined 45 degrees.
    ! The ballbar's fixed pivot is the origin of wobjBallbar; its length is read at
    ! every point (fine stops). Written for rapidfix; robot IRB 1600-10/1.45.
    PERS tooldata tBallbar:=[TRUE,[[0,0,100],[1,0,0,0]],[1.2,[0,0,60],[1,0,0,0],0,0,0]];
    ! The circle's plane: work object xy plane, tilted -45 degrees about the base y axis.
    PERS wobjdata wobjBallbar:=[FALSE,TRUE,"",[[850,80,450],[0.923879533,0,-0.382683432,0]],[[0,0,0],[1,0,0,0]]];
    CONST robtarget pBB00:=[[100,0,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB01:=[[98.4808,17.3648,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB02:=[[93.9693,34.202,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB03:=[[86.6025,50,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB04:=[[76.6044,64.2788,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB05:=[[64.2788,76.6044,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB06:=[[50,86.6025,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB07:=[[34.202,93.9693,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB08:=[[17.3648,98.4808,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB09:=[[0,100,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB10:=[[-17.3648,98.4808,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB11:=[[-34.202,93.9693,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB12:=[[-50,86.6025,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB13:=[[-64.2788,76.6044,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB14:=[[-76.6044,64.2788,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB15:=[[-86.6025,50,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB16:=[[-93.9693,34.202,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB17:=[[-98.4808,17.3648,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pBB18:=[[-100,0,0],[0,0.258819045,0.965925826,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];

    PROC main()
        ! approach above the first point, then the semicircle, then leave
        MoveJ Offs(pBB00,0,0,50), v200, z10, tBallbar\WObj:=wobjBallbar;
        MoveL pBB00, v50, fine, tBallbar\WObj:=wobjBallbar;
        WaitTime 0.5;
        MoveL pBB01, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB02, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB03, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB04, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB05, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB06, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB07, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB08, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB09, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB10, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB11, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB12, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB13, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB14, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB15, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB16, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB17, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL pBB18, v50, fine, tBallbar\WObj:=wobjBallbar;
        MoveL Offs(pBB18,0,0,50), v200, z10, tBallbar\WObj:=wobjBallbar;
    ENDPROC
ENDMODULE
